"""The gimbal through the real controller against the autopilots' own gimbal managers (``sitl``: skipped unless
built): ArduCopter with a servo mount, as ArduPilot's autotest sets one up; PX4 with gimbal protocol v2 input.

Each: MAVSDK finds the gimbal, control is taken, rates and angles move the attitude the autopilot reports (in
telemetry, and as the pose samples a ``sim:?mount=gimbal`` camera draws from), and the release leaves nobody in
control (GIMBAL_MANAGER_STATUS, read through MAVSDK)."""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager
from pathlib import Path
from typing import Any

import pytest
from mavsdk.asyncio.plugins.gimbal import ControlMode

from controllers.mavsdk.controller import MavsdkController
from tests.sitl import Sitl, arducopter, px4_sih

pytestmark = pytest.mark.sitl

ARDUPILOT_SERVO_MOUNT = {"MNT1_TYPE": 1, "SERVO5_FUNCTION": 8, "SERVO6_FUNCTION": 7, "SERVO7_FUNCTION": 6,
                         "MNT1_PITCH_MIN": -90, "MNT1_PITCH_MAX": 30, "MNT1_YAW_MIN": -180, "MNT1_YAW_MAX": 180}
"""A roll/pitch/yaw servo mount on outputs 5-7 (ArduPilot's ``setup_servo_mount``), pitch -90..30."""

PX4_GIMBAL_V2 = {"MNT_MODE_IN": 4, "MNT_MODE_OUT": 0}
"""Gimbal protocol v2 in, AUX out."""

AUTOPILOTS: dict[str, Callable[[Path], AbstractContextManager[Sitl]]] = {
    "ardupilot": lambda path: arducopter(path, ARDUPILOT_SERVO_MOUNT),
    "px4": lambda path: px4_sih(path, PX4_GIMBAL_V2),
}


@pytest.fixture(params=sorted(AUTOPILOTS))
def sitl(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[Sitl]:
    with AUTOPILOTS[request.param](tmp_path) as running:
        yield running


async def _until(check: Callable[[], bool], timeout_s: float, what: str, state: Callable[[], Any]) -> None:
    deadline = time.monotonic() + timeout_s
    while not check():
        if time.monotonic() > deadline:
            raise AssertionError(f"{what} not within {timeout_s:g} s; last: {state()}")
        await asyncio.sleep(0.1)


async def test_the_autopilot_s_gimbal_is_pointed_reported_and_released(sitl: Sitl) -> None:
    fc = MavsdkController()
    await fc.connect(sitl.connection_string, heartbeat_timeout=60.0)
    latest: dict[str, float] = {}

    async def read() -> None:
        async for update in fc.telemetry():
            latest.update({k: v for k, v in update.items() if k.startswith("gimbal_") or k == "yaw_deg"})

    reader = asyncio.create_task(read())
    try:
        await fc.point_gimbal("angle", -20.0, 0.0)  # waits for MAVSDK to find the gimbal, takes control
        await _until(lambda: abs(latest.get("gimbal_pitch_deg", 99) + 20) < 1, 10, "pitch -20", lambda: latest)
        start = latest["gimbal_pitch_deg"]
        for _ in range(15):  # 1.5 s down at 10 deg/s
            await fc.point_gimbal("rate", -10.0, 0.0)
            await asyncio.sleep(0.1)
        await _until(lambda: latest["gimbal_pitch_deg"] < start - 8, 3, "turning down", lambda: latest)
        await fc.point_gimbal("angle", -45.0, 20.0)
        await _until(lambda: abs(latest["gimbal_pitch_deg"] + 45) < 1
                     and abs((latest["gimbal_yaw_deg"] - latest["yaw_deg"] - 20 + 180) % 360 - 180) < 2,
                     10, "pitch -45, yaw 20 right of the nose", lambda: latest)
        async with asyncio.timeout(5), contextlib.aclosing(fc.pose_samples()) as samples:
            async for sample in samples:  # what the sim: camera on the gimbal draws from, yaw from the nose
                if sample.kind == "gimbal":
                    assert sample.values[1:] == pytest.approx((-45.0, 20.0), abs=1.0)
                    break
        assert fc._gimbal is not None and fc._gimbal.gimbal_id is not None
        plugin, gimbal_id = fc._gimbal._plugin, fc._gimbal.gimbal_id
        await _until(lambda: fc.gimbal_controlled, 1, "controlled", lambda: None)
        assert (await plugin.get_control_status(gimbal_id)).control_mode == ControlMode.PRIMARY
        await fc.release_gimbal()
        deadline = time.monotonic() + 5
        while (mode := (await plugin.get_control_status(gimbal_id)).control_mode) != ControlMode.NONE:
            assert time.monotonic() < deadline, f"still in control after the release: {mode}"
            await asyncio.sleep(0.2)
    finally:
        reader.cancel()
        await asyncio.gather(reader, return_exceptions=True)
        await fc.close()
