"""Real PX4 SITL (``sitl``, skipped unless built): booted with a failsafe that would fly a dead client's setpoint
for 10 s and then return home, uav-tui sets it at connect; after SIGKILL mid-vector PX4 holds where it is."""

from __future__ import annotations

import asyncio
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from controllers.mavsdk_controller import MavsdkController
from tests.core.flight_helpers import STEERING_PROCESSOR
from tests.sitl import px4_sitl

pytestmark = pytest.mark.sitl
ROOT = Path(__file__).resolve().parents[2]
SCRIPT = "wait 8\narm\ntakeoff 3\nwait 10\nf 1\nautonomy on\nwait 120\n"


def wait_line(process: subprocess.Popen[str], text: str, timeout: float) -> list[str]:
    seen, deadline = [], time.monotonic() + timeout
    assert process.stdout is not None
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        if not line:
            break
        seen.append(line)
        if text in line:
            return seen
    raise AssertionError(f"no {text!r} from uav-tui:\n{''.join(seen)}")


async def mode_and_speed_after(address: str, killed: float) -> tuple[str, float, float]:
    """Reconnect as uav-tui would; wait until PX4 left OFFBOARD and slowed down; (mode, speed, seconds since kill)."""
    fc = MavsdkController()
    await fc.connect(address, heartbeat_timeout=10.0)
    mode, speed = "", math.inf
    try:
        async with asyncio.timeout(20):
            async for update in fc.telemetry():
                mode = update.get("flight_mode", mode)
                if "vn_ms" in update and update["vn_ms"] is not None:
                    speed = math.hypot(update["vn_ms"], update["ve_ms"])
                if mode and mode != "OFFBOARD" and speed < 0.3:
                    return mode, speed, time.monotonic() - killed
    finally:
        await fc.close()
    raise AssertionError(f"PX4 still in {mode} at {speed:.2f} m/s")


def test_px4_sigkill_mid_vector_holds(tmp_path: Path) -> None:
    (tmp_path / "steering.py").write_text(STEERING_PROCESSOR)
    (tmp_path / "flight.txt").write_text(SCRIPT)
    with px4_sitl(tmp_path / "px4", {"COM_OF_LOSS_T": 10, "COM_OBL_RC_ACT": 3}) as address:
        process = subprocess.Popen(
            [sys.executable, "-m", "uav_tui", "--no-ui", "--fc", address, "--source",
             "synthetic:?width=160&height=120", "--processor", "steering.py:Steering", "--script", "flight.txt",
             "--no-record"],
            cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)}, stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT, text=True)
        try:
            seen = wait_line(process, "autonomy ON", 90)
            seen += wait_line(process, "OFFBOARD", 15)
            time.sleep(1.0)
            process.send_signal(signal.SIGKILL)
            killed = time.monotonic()
            process.communicate(timeout=10)
        finally:
            process.kill()
            process.communicate()
        mode, _speed, after_s = asyncio.run(mode_and_speed_after(address, killed))
    assert mode == "HOLD"  # not RETURN_TO_LAUNCH (COM_OBL_RC_ACT 3)
    assert after_s < 8  # its 10 s COM_OF_LOSS_T would still be flying the vector
    assert "set COM_OF_LOSS_T 10 -> 1, COM_OBL_RC_ACT 3 -> 5" in "".join(seen)
