"""The optional capabilities the platform asks each controller for with ``isinstance``: a built-in controller
that loses one (a rename) would silently lose the feature, so each is pinned here."""

from __future__ import annotations

from pathlib import Path

from controllers.base import (
    BlockingCalls,
    FailsafeCheck,
    FlightController,
    LandingTargets,
    OwnModes,
    PoseFeed,
    PrecisionLanding,
    RecordedVehicle,
    SimulatorOwner,
)
from controllers.mavsdk.controller import MavsdkController
from controllers.replay import ReplayController
from controllers.sim.launcher import SimVehicle
from controllers.sim_controller import SimController
from uav_tui.config import RecordingConfig
from uav_tui.recording import Recorder

CAPABILITIES = (FailsafeCheck, PoseFeed, OwnModes, LandingTargets, PrecisionLanding, BlockingCalls, SimulatorOwner,
                RecordedVehicle)


def _capabilities(controller: object) -> set[type]:
    return {capability for capability in CAPABILITIES if isinstance(controller, capability)}


def test_a_mavlink_controller_checks_failsafes_feeds_poses_and_says_its_modes() -> None:
    controller = MavsdkController()
    assert isinstance(controller, FlightController)
    assert _capabilities(controller) == {FailsafeCheck, PoseFeed, OwnModes, LandingTargets, PrecisionLanding,
                                         BlockingCalls}
    assert controller.own_modes == frozenset({"HOLD", "OFFBOARD"}) and controller.unfinished_calls == []


def test_the_built_in_vehicle_owns_its_simulator() -> None:
    controller = SimController(SimVehicle())
    assert _capabilities(controller) == {FailsafeCheck, PoseFeed, OwnModes, LandingTargets, PrecisionLanding,
                                         BlockingCalls, SimulatorOwner}
    assert controller.sim.exit_status() is None  # never started


def test_a_replay_is_a_recorded_vehicle_and_nothing_more(tmp_path: Path) -> None:
    recorder = Recorder.open(RecordingConfig(runs_dir=str(tmp_path)), {}, telemetry_expected=False)
    recorder.close()
    controller = ReplayController(recorder.run_dir, None)
    assert isinstance(controller, FlightController)
    assert _capabilities(controller) == {RecordedVehicle}
    assert controller.run_dir == recorder.run_dir
