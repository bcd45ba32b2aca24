"""The offboard-loss failsafe check against the real autopilots (``sitl``: skipped unless they are built)."""

from __future__ import annotations

from pathlib import Path

import pytest

from controllers.mavsdk_controller import MavsdkController
from tests.sitl import arducopter, px4_sih

pytestmark = pytest.mark.sitl


async def check(address: str, tune: bool) -> tuple[dict, dict, list]:
    fc = MavsdkController()
    await fc.connect(address, heartbeat_timeout=60.0)
    try:
        report = await fc.check_failsafe(2.0, tune=tune)
        again = await fc.check_failsafe(2.0, tune=False)
    finally:
        await fc.close()
    assert again.ok, again.problems  # what it set is what the autopilot now holds
    return report.found, report.changed, report.problems


async def test_arducopter_guid_timeout_is_set(tmp_path: Path) -> None:
    with arducopter(tmp_path) as sitl:
        found, changed, problems = await check(sitl.connection_string, tune=True)
    assert problems == []
    assert changed == {"GUID_TIMEOUT": (found["GUID_TIMEOUT"], 1.0)}  # default 3 s: 3.8 s of flight after SIGKILL


async def test_px4_defaults_pass(tmp_path: Path) -> None:
    with px4_sih(tmp_path) as sitl:
        found, changed, problems = await check(sitl.connection_string, tune=False)
    assert problems == [] and changed == {}
    assert found == {"COM_OF_LOSS_T": 1.0, "COM_OBL_RC_ACT": 0.0}


async def test_px4_too_slow_failsafe_is_set(tmp_path: Path) -> None:
    with px4_sih(tmp_path, {"COM_OF_LOSS_T": 10, "COM_OBL_RC_ACT": 3}) as sitl:
        found, changed, problems = await check(sitl.connection_string, tune=True)
    assert problems == []
    assert found == {"COM_OF_LOSS_T": 10.0, "COM_OBL_RC_ACT": 3.0}
    assert changed == {"COM_OF_LOSS_T": (10.0, 1.0), "COM_OBL_RC_ACT": (3.0, 5.0)}
