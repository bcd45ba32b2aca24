"""Real SITLs (``sitl``, skipped unless built): booted with an offboard-loss failsafe that would fly a dead
client's last velocity far too long, uav-tui sets it at connect; after SIGKILL mid-vector the vehicle stops."""

from __future__ import annotations

import asyncio
import math
import signal
import subprocess
import time
from pathlib import Path

import pytest

from controllers.mavsdk.controller import MavsdkController
from tests.core.flight_helpers import start_steering_flight
from tests.sitl import arducopter, px4_sih

pytestmark = pytest.mark.sitl

CASES = {
    # PX4: 10 s of the last setpoint, then RETURN; it should hold after 1 s.
    "px4": (px4_sih, {"COM_OF_LOSS_T": 10, "COM_OBL_RC_ACT": 3}, 8,
            "set COM_OF_LOSS_T 10 -> 1, COM_OBL_RC_ACT 3 -> 5"),
    # ArduCopter: GUIDED flies a velocity target for GUID_TIMEOUT (5 s here), then stops in GUIDED.
    # GUIDED arming works only ~40 s after boot.
    "arducopter": (arducopter, {"GUID_TIMEOUT": 5}, 45, "set GUID_TIMEOUT 5 -> 1"),
}


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


async def stopped_after(address: str, killed: float, autopilot: str) -> tuple[str, float]:
    """Reconnect as uav-tui would; wait until the vehicle is slower than 0.3 m/s (and, on PX4, out of
    OFFBOARD: ArduCopter stays in GUIDED); returns (flight mode, seconds since the kill)."""
    fc = MavsdkController()
    await fc.connect(address, heartbeat_timeout=10.0)
    mode, speed = "", math.inf
    try:
        async with asyncio.timeout(30):
            async for update in fc.telemetry():
                mode = update.get("flight_mode", mode)
                if update.get("vn_ms") is not None and update.get("ve_ms") is not None:
                    speed = math.hypot(update["vn_ms"], update["ve_ms"])
                if mode and speed < 0.3 and (autopilot == "arducopter" or mode != "OFFBOARD"):
                    return mode, time.monotonic() - killed
    finally:
        await fc.close()
    raise AssertionError(f"still in {mode} at {speed:.2f} m/s")


@pytest.mark.parametrize("autopilot", list(CASES))
def test_sigkill_mid_vector_stops_the_vehicle(tmp_path: Path, autopilot: str) -> None:
    start_sitl, params, boot_s, tuned = CASES[autopilot]
    script = f"wait {boot_s}\narm\ntakeoff 3\nwait 10\nf 1\nautonomy on\nwait 120\n"
    workdir = tmp_path / "sitl"
    workdir.mkdir()
    with start_sitl(workdir, params) as sitl:
        address = sitl.connection_string
        process = start_steering_flight(tmp_path, address, script)
        try:
            seen = wait_line(process, "autonomy ON", boot_s + 60)
            seen += wait_line(process, "s (executed)", 15)  # a vector flies (status: "auto ON vec ... 2.0s (executed)")
            time.sleep(1.0)
            process.send_signal(signal.SIGKILL)
            killed = time.monotonic()
            process.communicate(timeout=10)
        finally:
            process.kill()
            process.communicate()
        mode, after_s = asyncio.run(stopped_after(address, killed, autopilot))
    if autopilot == "px4":
        assert mode == "HOLD"  # not RETURN_TO_LAUNCH (COM_OBL_RC_ACT 3)
    assert after_s < 4.5  # the booted failsafe would still be flying the vector (reconnecting takes ~1-2 s)
    assert tuned in "".join(seen)
