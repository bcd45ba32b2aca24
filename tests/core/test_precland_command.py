"""``precland``: refused, saying why, without a landing target or with the autopilot not set up; otherwise the
autopilot lands on the target, and any other vehicle command, or a pilot's mode switch, turns it off. Through a
real core and the real MAVSDK controller on the built-in simulator."""

from __future__ import annotations

import asyncio
import time
from pathlib import Path
from typing import Any

import pytest

from controllers.precland_requirements import PrecisionLandingError
from controllers.sim.launcher import SimVehicle
from tests.core.flight_helpers import flying_core, steering_config, wait_until
from uav_tui.core import UavCore
from uav_tui.errors import UavError
from uav_tui.events import EventLog
from uav_tui.headless import format_status
from uav_tui.relays.precland import LandingTargetFeed

PAD_PROCESSOR = '''
from uav_values.landing_target import LandingTarget


class Pad:
    """Test processor: after F1 it sees a pad straight along the optical axis, 3 m away; F2 loses it; F3 raises."""

    def __init__(self):
        self.tmMgr = None
        self.visible = False
        self.failing = False

    def photo_processing(self, frame):
        if self.failing:
            raise RuntimeError("simulated algorithm failure")

    def customize_processing(self, id):
        self.visible = id in (1, 3)
        self.failing = id == 3

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
@pytest.mark.parametrize("isolation", ["process", "thread"])
async def test_precland_checks_the_target_and_the_plnd_parameters_then_lands(tmp_path: Path, sim_vehicle: SimVehicle,
                                                                             isolation: str) -> None:
    async with flying_core(tmp_path, vehicle=sim_vehicle, processor=pad_processor(tmp_path), camera_hfov=60.0,
                           camera_mount="down", isolation=isolation) as core:
        with pytest.raises(UavError, match="has not seen a landing target yet: bring the pad into view"):
            await core.execute("precland")
        await core.execute("f 1")
        await wait_until(lambda: core.landing.last_seen_ns is not None, 5, "the pad seen")
        await core.execute("f 2")  # lost
        await asyncio.sleep(1.3)
        with pytest.raises(UavError, match=r"no landing target in the last 1 s \(the last one 1\.\d s ago\)"):
            await core.execute("precland")
        await core.execute("f 1")
        await asyncio.sleep(0.3)
        assert core.status().landing_targets_sent == 0  # seen, not sent: precland is off
        with pytest.raises(PrecisionLandingError, match="PLND_ENABLED = 0, precision landing needs PLND_ENABLED = 1"):
            await core.execute("precland")
        status = core.status()
        assert not status.precland and status.precland_stop_reason == "precland failed"
        assert core.truth.latest()["mode"] == "GUIDED"  # type: ignore[attr-defined]

        await core.controller._param.set_param_int("PLND_ENABLED", 1)  # type: ignore[union-attr]
        assert "PLND_ENABLED=1, PLND_TYPE=1" in await core.execute("precland")
        assert core.status().precland and core.mode_left_at_exit() == "LAND"
        await wait_until(lambda: core.truth.latest()["mode"] == "LAND", 5, "LAND")  # type: ignore[attr-defined]
        await wait_until(lambda: core.status().landing_targets_sent >= 5, 5, "landing targets sent")
        assert "| precland ON " in format_status(core.status(), 1.0)

        await core.execute("hold")
        status = core.status()
        assert not status.precland and status.precland_stop_reason == "pre-empted by operator command 'hold'"
        await asyncio.sleep(0.3)  # a send already under way ends
        sent = core.status().landing_targets_sent
        await asyncio.sleep(0.5)
        assert core.status().landing_targets_sent == sent, "landing targets still sent after hold"

        assert "precision landing" in await core.execute("precland")
        await core.execute("f 3")  # the processor keeps raising: precland stops as autonomy would
        await wait_until(lambda: not core.status().precland, 5, "precland off")
        assert "processor raised" in core.status().precland_stop_reason


def landing_targets_since(sim: SimVehicle, since_mono_ns: int) -> list[dict[str, Any]]:
    """The LANDING_TARGETs the simulator received after ``since_mono_ns`` (its own log, not the platform's)."""
    reply = sim.truth().request({"cmd": "landing_targets", "since_mono_ns": since_mono_ns})
    return reply["records"]


@pytest.mark.timeout(120)
@pytest.mark.parametrize("sim_vehicle", [{"autopilot": "ardupilot", "extra_args": ["--plnd-enabled"]}],
                         indirect=True)
async def test_a_pilot_taking_the_vehicle_out_of_land_stops_the_landing_targets(tmp_path: Path,
                                                                                sim_vehicle: SimVehicle) -> None:
    async with flying_core(tmp_path, vehicle=sim_vehicle, processor=pad_processor(tmp_path), camera_hfov=60.0,
                           camera_mount="down") as core:
        truth = core.truth  # type: ignore[attr-defined]
        await core.execute("f 1")
        await wait_until(lambda: core.landing.last_seen_ns is not None, 5, "the pad seen")
        engaged_ns = time.monotonic_ns()
        await core.execute("precland")
        await wait_until(lambda: core.telemetry.snapshot().flight_mode == "LAND", 5, "LAND reported")
        await asyncio.sleep(0.5)
        assert core.status().precland and len(landing_targets_since(sim_vehicle, engaged_ns)) >= 5

        truth.request({"cmd": "rc_throttle", "pwm": 1500})  # the pilot's stick at mid: LOITER holds the height
        truth.request({"cmd": "rc_mode", "mode": "LOITER"})  # the pilot's mode switch: no MAVLink client asked
        await wait_until(lambda: not core.status().precland, 5, "precland off")
        stopped_ns = time.monotonic_ns()
        reason = core.status().precland_stop_reason
        assert reason == "the vehicle left LAND for HOLD: a pilot, a mission or a failsafe took it"  # LOITER: HOLD
        said = [e.message for e in core.events.recent if e.level == "warning"]
        assert f"precland off, landing targets no longer sent: {reason}" in said
        await asyncio.sleep(1.5)
        late = landing_targets_since(sim_vehicle, stopped_ns + 300_000_000)  # a send under way may still arrive
        assert late == [], f"{len(late)} LANDING_TARGETs reached the autopilot after precland stopped"
        assert truth.latest()["mode"] == "LOITER"  # the pilot keeps the vehicle: no hold from the platform


def test_precland_ends_when_the_vehicle_leaves_its_landing_mode_or_never_reports_it() -> None:
    now = [0]
    feed = LandingTargetFeed(EventLog(), clock=lambda: now[0])
    feed.engage()
    modes = frozenset({"LAND"})
    assert feed.left_mode("OFFBOARD", modes) == ""  # the old mode, reported before the switch shows
    now[0] = 2_000_000_000
    assert feed.left_mode("LAND", modes) == "" and feed.left_mode(None, modes) == ""
    now[0] = 60_000_000_000
    assert feed.left_mode("LAND", modes) == ""
    assert feed.left_mode("HOLD", modes) == "the vehicle left LAND for HOLD: a pilot, a mission or a failsafe took it"
    feed.engage()
    now[0] += 3_100_000_000
    assert feed.left_mode("HOLD", modes) == "the vehicle did not report LAND within 3 s of precland (it reports HOLD)"


@pytest.mark.timeout(120)
@pytest.mark.parametrize("sim_vehicle", [{"autopilot": "px4"}], indirect=True)
async def test_px4_precision_land_is_reported_by_name_and_a_pilot_leaving_it_stops_the_targets(
        tmp_path: Path, sim_vehicle: SimVehicle) -> None:
    """PX4's Precision Land (main 4, sub 9) is UNKNOWN to MAVSDK: the platform names it from the HEARTBEAT."""
    async with flying_core(tmp_path, vehicle=sim_vehicle, processor=pad_processor(tmp_path), camera_hfov=60.0,
                           camera_mount="down") as core:
        truth = core.truth  # type: ignore[attr-defined]
        await core.execute("f 1")
        await wait_until(lambda: core.landing.last_seen_ns is not None, 5, "the pad seen")
        assert "Precision Land" in await core.execute("precland")
        await wait_until(lambda: core.telemetry.snapshot().flight_mode == "PRECISION_LAND", 5,
                         "PRECISION_LAND reported")
        assert truth.latest()["mode"] == "PRECLAND"
        await wait_until(lambda: core.status().landing_targets_sent >= 5, 5, "landing targets sent")
        assert core.status().precland and core.mode_left_at_exit() == "PRECISION_LAND"

        truth.request({"cmd": "rc_mode", "mode": "POSCTL"})  # the pilot's mode switch: no MAVLink client asked
        await wait_until(lambda: not core.status().precland, 5, "precland off")
        reason = core.status().precland_stop_reason
        assert reason == "the vehicle left PRECISION_LAND for POSCTL: a pilot, a mission or a failsafe took it"
