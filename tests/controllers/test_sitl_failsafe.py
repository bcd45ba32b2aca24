"""The offboard-loss failsafe check against the real autopilots (``sitl``: skipped unless they are built)."""

from __future__ import annotations

from pathlib import Path

import pytest

from controllers.mavsdk.controller import MavsdkController
from tests.sitl import arducopter, px4_sih

pytestmark = pytest.mark.sitl


async def check(address: str, tune: bool) -> tuple[dict, dict, list, str]:
    fc = MavsdkController()
    await fc.connect(address, heartbeat_timeout=60.0)
    try:
        report = await fc.check_failsafe(2.0, tune=tune)
        again = await fc.check_failsafe(2.0, tune=False)
    finally:
        await fc.close()
    assert again.ok, again.problems  # what it set is what the autopilot now holds
    return report.found, report.changed, report.problems, report.radio


async def test_arducopter_guid_timeout_is_set(tmp_path: Path) -> None:
    with arducopter(tmp_path) as sitl:
        found, changed, problems, _ = await check(sitl.connection_string, tune=True)
    assert problems == []
    assert changed == {"GUID_TIMEOUT": (found["GUID_TIMEOUT"], 1.0)}  # default 3 s: 3.8 s of flight after SIGKILL
    assert found["GUID_OPTIONS"] == 0  # GUIDED stabilises position and velocity: a lapsed target holds


async def test_px4_default_position_mode_without_a_radio_is_set_to_hold(tmp_path: Path) -> None:
    """PX4's default offboard-loss action flies the sticks: with no radio SITL sank 4.4 m in 8 s in POSCTL."""
    with px4_sih(tmp_path) as sitl:
        found, changed, problems, radio = await check(sitl.connection_string, tune=True)
    assert problems == []
    assert found == {"COM_OF_LOSS_T": 1.0, "COM_OBL_RC_ACT": 0.0}
    assert changed == {"COM_OBL_RC_ACT": (0.0, 5.0)}
    assert radio == "no radio (SYS_STATUS: no RC receiver; COM_RC_IN_MODE=1)"  # SITL's rcS: joystick only


async def test_px4_too_slow_failsafe_is_set(tmp_path: Path) -> None:
    with px4_sih(tmp_path, {"COM_OF_LOSS_T": 10, "COM_OBL_RC_ACT": 3}) as sitl:
        found, changed, problems, _ = await check(sitl.connection_string, tune=True)
    assert problems == []
    assert found == {"COM_OF_LOSS_T": 10.0, "COM_OBL_RC_ACT": 3.0}
    assert changed == {"COM_OF_LOSS_T": (10.0, 1.0), "COM_OBL_RC_ACT": (3.0, 5.0)}
