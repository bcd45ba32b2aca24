"""The gimbal driven by a processor on the simulated vehicle, reached over MAVLink only (gimbal protocol v2 through
MAVSDK's Gimbal plugin): a tracker keeps a driving car centred with the gimbal while the vehicle hovers, and every
stop (land, hold, processor fault, exit) stops the gimbal and releases control. The truth channel is the test's."""

from __future__ import annotations

import asyncio
import math
import time
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

from controllers.sim.launcher import SimVehicle
from sources.sim_geometry import Pose, project_ground_point
from tests.core.flight_helpers import RENDERER_STALL_S, flying_core, wait_until, what_happened
from uav_tui.recorded import dataset
from uav_tui.relays.registry import gimbal_relay

WIDTH, HEIGHT = 480, 360
SOURCE = f"sim:?width={WIDTH}&height={HEIGHT}&mount=gimbal&targets=1&target_speed=1.0"
HOVER = {"cmd": "teleport", "n": 0.0, "e": -14.0, "d": -20.0, "yaw": 90.0}
"""20 m up facing east, 8-20 m from the car's 6 m ring: the gimbal, 45 degrees down ahead, sees the car drive across
its view 45-68 degrees below the horizon."""

POINTING_PROCESSOR = '''
from processors import GimbalPointing

class Pointer:
    """Test processor: F1 turns the gimbal right at 20 deg/s, F3 raises on every frame."""

    def __init__(self):
        self.tmMgr = None
        self.mode = "idle"

    def photo_processing(self, frame):
        if self.mode == "raise":
            raise RuntimeError("simulated algorithm failure")

    def customize_processing(self, id):
        self.mode = {1: "turn", 3: "raise"}[id]

    def getGimbalPointing(self):
        return GimbalPointing.rates(0.0, 20.0) if self.mode == "turn" else None
'''


def _car_pixel(props: dict[str, Any], camera: Any) -> tuple[float, float] | None:
    target = props["targets"][0]
    return project_ground_point(target["n"], target["e"], Pose.from_mapping(props["pose"]), camera)


@pytest.mark.parametrize("processor", ["nanotrack", "csrt"])
async def test_a_tracker_keeps_a_driving_car_centred_with_the_gimbal_while_the_vehicle_hovers(
        tmp_path: Path, sim_vehicle: SimVehicle, processor: str) -> None:
    async with flying_core(tmp_path, altitude=3, processor=processor, processor_args={"follow": "gimbal"},
                           source=SOURCE, vehicle=sim_vehicle, record=True, runs_dir=str(tmp_path),
                           camera_stall=RENDERER_STALL_S) as core:
        truth, source = core.truth, core.source
        await asyncio.to_thread(truth.request, HOVER)
        await wait_until(lambda: abs(truth.latest()["d"] + 20) < 0.3, 10, "the hover at 20 m")

        def in_view() -> bool:
            pixel = _car_pixel(source.get_properties(), source.camera)
            return pixel is not None and 80 < pixel[0] < WIDTH - 80 and 80 < pixel[1] < HEIGHT - 80

        await wait_until(in_view, 40, "the car driving into view")  # the gimbal still looks where it booted
        props = source.get_properties()
        pose = Pose.from_mapping(props["pose"])
        outline = [project_ground_point(n, e, pose, source.camera) for n, e in props["targets"][0]["corners"]]
        x, y, w, h = cv2.boundingRect(np.array(outline, np.float32))
        await core.execute(f"roi {x} {y} {w} {h}")
        await core.execute("autonomy on")
        hover, start = truth.latest(), time.monotonic()
        first = props["targets"][0]
        offsets: list[tuple[float, float, str]] = []
        centred_at: float | None = None  # the car starts off centre: the gimbal brings it there first, at the
        while centred_at is None or time.monotonic() - centred_at < 17:  # machine's pace; then 17 s centred
            await asyncio.sleep(0.2)
            assert time.monotonic() - start < 40, f"the gimbal never centred the car; {what_happened(core)}"
            props = source.get_properties()
            pixel = _car_pixel(props, source.camera)
            assert pixel is not None, f"the car is behind the camera: {props['pose']}"
            du, dv = abs(pixel[0] - WIDTH / 2) / WIDTH, abs(pixel[1] - HEIGHT / 2) / HEIGHT
            if centred_at is None and du <= 0.1 and dv <= 0.1:
                centred_at = time.monotonic()
            if centred_at is not None:  # from then on it must stay centred
                offsets.append((du, dv, f"{time.monotonic() - start:.1f} s: car at {pixel[0]:.0f},{pixel[1]:.0f}"))
        last = props["targets"][0]
        assert math.hypot(last["n"] - first["n"], last["e"] - first["e"]) > 10  # the car drove across the view ...
        turned = truth.latest()
        off = [text for du, dv, text in offsets if du > 0.1 or dv > 0.1]
        assert not off, f"the car was more than 10 % of the frame off centre: {off[:5]}...; {what_happened(core)}"
        assert math.hypot(turned["n"] - hover["n"], turned["e"] - hover["e"]) < 0.5  # the vehicle hovered
        assert core.gate.executed == 0 and turned["gimbal_controlled"]
        assert gimbal_relay(core.relays) is not None and gimbal_relay(core.relays).sent > 30
        status = core.status().gimbal_summary()
        assert status.startswith("gimbal P-") and "controlled" in status, status
        assert core.status().as_dict()["gimbal"].startswith("gimbal P-")  # --json and the web page's status line
        run_dir = core.recorder.run_dir  # type: ignore[union-attr]
    run = dataset.load(run_dir)
    sent = run.frames[run.frames.gimbal == "sent"]
    assert len(sent) > 30 and sent.gimbal_pitch_deg.notna().all()  # the gimbal's attitude at each capture
    assert run.telemetry.gimbal_yaw_deg.notna().any()


@pytest.mark.parametrize("stop", ["land", "hold", "processor fault", "exit"])
async def test_every_stop_stops_the_gimbal_and_releases_control(tmp_path: Path, sim_vehicle: SimVehicle,
                                                                stop: str) -> None:
    (tmp_path / "pointer.py").write_text(POINTING_PROCESSOR)
    core_context = flying_core(tmp_path, processor=f"{tmp_path / 'pointer.py'}:Pointer", vehicle=sim_vehicle)
    core = await core_context.__aenter__()
    truth = core.truth
    try:
        await core.execute("f 1")
        await core.execute("autonomy on")
        await wait_until(lambda: truth.latest()["gimbal_controlled"] and truth.latest()["gimbal_yaw_rate"] > 19, 5,
                         "the gimbal turning under the processor's control")
        if stop == "processor fault":
            await core.execute("f 3")
        elif stop == "exit":
            await core.stop("test exit")
        else:
            await core.execute(stop)
        await wait_until(lambda: not truth.latest()["gimbal_controlled"], 3, f"control released on {stop}")
        await asyncio.sleep(0.2)
        state = truth.latest()
        assert (state["gimbal_pitch_rate"], state["gimbal_yaw_rate"]) == (0.0, 0.0)
        assert not core.gate.enabled
        released = [e.message for e in core.events.recent if e.message.startswith("gimbal stopped and released")]
        assert len(released) == 1, released
        await asyncio.sleep(0.5)  # and it stays released: no setpoint takes control back
        assert not truth.latest()["gimbal_controlled"]
    finally:
        await core_context.__aexit__(None, None, None)


async def test_nothing_is_sent_while_autonomy_is_off(tmp_path: Path, sim_vehicle: SimVehicle) -> None:
    (tmp_path / "pointer.py").write_text(POINTING_PROCESSOR)
    async with flying_core(tmp_path, processor=f"{tmp_path / 'pointer.py'}:Pointer", vehicle=sim_vehicle) as core:
        await core.execute("f 1")
        await wait_until(lambda: core.last is not None and core.last.gimbal, 5, "a frame judged")
        await asyncio.sleep(0.5)
        assert core.last.gimbal == "not sent: autonomy off"
        assert not core.truth.latest()["gimbal_controlled"] and gimbal_relay(core.relays).sent == 0
