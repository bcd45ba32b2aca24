"""Real SITLs (``sitl``, skipped unless built): a script that ends with ``land`` leaves the autopilot landing.

uav-tui holds the vehicle before it exits (safety rule 6) unless the vehicle lands, returns, flies a mission or
is flown by hand: there a hold would leave it hovering with nobody connected."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from controllers.mavsdk.controller import MavsdkController
from tests.core.flight_helpers import start_steering_flight
from tests.sitl import arducopter, px4_sih

pytestmark = pytest.mark.sitl

CASES = {"px4": (px4_sih, 8), "arducopter": (arducopter, 45)}
"""The SITL and how long after its boot it can arm (ArduCopter: GUIDED only ~40 s after boot)."""


async def modes_until_landed(address: str) -> list[str]:
    """Reconnect as a ground station; the flight modes reported until the vehicle is on the ground."""
    fc = MavsdkController()
    await fc.connect(address, heartbeat_timeout=10.0)
    modes: list[str] = []
    try:
        async with asyncio.timeout(60):
            async for update in fc.telemetry():
                if (mode := update.get("flight_mode")) and mode not in modes[-1:]:
                    modes.append(mode)
                if update.get("in_air") is False:
                    return modes
    except TimeoutError:
        raise AssertionError(f"still in the air after 60 s; modes seen: {modes}") from None
    finally:
        await fc.close()
    raise AssertionError(f"telemetry ended in the air; modes seen: {modes}")


@pytest.mark.parametrize("autopilot", list(CASES))
def test_a_script_ending_with_land_leaves_the_vehicle_landing(tmp_path: Path, autopilot: str) -> None:
    start_sitl, boot_s = CASES[autopilot]
    workdir = tmp_path / "sitl"
    workdir.mkdir()
    with start_sitl(workdir, {}) as sitl:
        process = start_steering_flight(tmp_path, sitl.connection_string,
                                        f"wait {boot_s}\narm\ntakeoff 5\nwait 12\nland\nwait 1\n")
        try:
            out, _ = process.communicate(timeout=boot_s + 60)
        finally:
            process.kill()
            process.communicate()
        assert process.returncode == 0, out
        assert "vehicle left in LAND mode at exit" in out, out
        modes = asyncio.run(modes_until_landed(sitl.connection_string))
    assert modes[0] == "LAND" and "HOLD" not in modes, modes
