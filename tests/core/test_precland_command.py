"""``precland``: refused, saying why, without a landing target or with the autopilot not set up; otherwise the
autopilot lands on the target, and any other vehicle command turns it off. Through a real core and the real
MAVSDK controller on the built-in simulator."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from controllers.precland import PrecisionLandingError
from controllers.sim.launcher import SimVehicle
from tests.core.flight_helpers import flying_core, steering_config, wait_until
from uav_tui.core import UavCore
from uav_tui.errors import UavError

PAD_PROCESSOR = '''
from processors.landing_target import LandingTarget


class Pad:
    """Test processor: after F1 it sees a pad straight along the optical axis, 3 m away; F2 loses it."""

    def __init__(self):
        self.tmMgr = None
        self.visible = False

    def photo_processing(self, frame):
        pass

    def customize_processing(self, id):
        self.visible = id == 1

    def getLandingTarget(self):
        return LandingTarget((0.0, 0.0, 1.0), 3.0) if self.visible else None
'''


def pad_processor(tmp_path: Path) -> str:
    (tmp_path / "pad.py").write_text(PAD_PROCESSOR)
    return f"{tmp_path / 'pad.py'}:Pad"


@pytest.mark.timeout(60)
async def test_precland_needs_a_processor_that_reports_landing_targets(tmp_path: Path) -> None:
    core = UavCore(steering_config(tmp_path))
    await core.start()
    try:
        with pytest.raises(UavError, match=r"steering\.py:Steering has no getLandingTarget\(\) method"):
            await core.execute("precland")
        assert not core.status().precland
    finally:
        await core.stop("test finished")


@pytest.mark.timeout(120)
@pytest.mark.parametrize("sim_vehicle", [{"autopilot": "ardupilot"}], indirect=True)
async def test_precland_checks_the_target_and_the_plnd_parameters_then_lands(tmp_path: Path,
                                                                             sim_vehicle: SimVehicle) -> None:
    async with flying_core(tmp_path, vehicle=sim_vehicle, processor=pad_processor(tmp_path)) as core:
        with pytest.raises(UavError, match="has not seen a landing target yet: bring the pad into view"):
            await core.execute("precland")
        core.landing.seen(time.monotonic_ns() - 2_000_000_000)
        with pytest.raises(UavError, match=r"no landing target in the last 1 s \(the last one 2\.\d s ago\)"):
            await core.execute("precland")
        core.landing.seen(time.monotonic_ns())
        with pytest.raises(PrecisionLandingError, match="PLND_ENABLED = 0, precision landing needs PLND_ENABLED = 1"):
            await core.execute("precland")
        status = core.status()
        assert not status.precland and status.precland_stop_reason == "precland failed"
        assert core.truth.latest()["mode"] == "GUIDED"  # type: ignore[attr-defined]

        await core.controller._param.set_param_int("PLND_ENABLED", 1)  # type: ignore[union-attr]
        core.landing.seen(time.monotonic_ns())
        assert "PLND_ENABLED=1, PLND_TYPE=1" in await core.execute("precland")
        assert core.status().precland and core.mode_left_at_exit() == "LAND"
        await wait_until(lambda: core.truth.latest()["mode"] == "LAND", 5, "LAND")  # type: ignore[attr-defined]

        await core.execute("hold")
        status = core.status()
        assert not status.precland and status.precland_stop_reason == "pre-empted by operator command 'hold'"
