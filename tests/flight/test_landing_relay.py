"""The landing-target relay's refusals (issue 47): a target that cannot be true is never counted as seen, the reason
is what ``precland`` and the status say, and a run of them turns ``precland`` off; the processor's own reason for
giving none is said too. On the relay's own parts but the gate and the sender: it reads only its landing feed,
telemetry and camera here."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from processors import LandingTarget
from processors.outputs import FrameOutputs
from sources.buffer import Frame
from uav_tui.camera.active import ActiveCamera
from uav_tui.config import CameraConfig
from uav_tui.errors import UavError
from uav_tui.events import EventLog
from uav_tui.flight.plausibility import REFUSALS_TO_STOP
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.wire import FrameOutcome
from uav_tui.relays.landing_target import LandingTargetRelay
from uav_tui.relays.precland import LandingTargetFeed
from uav_values.camera import CameraModel


class _Core:
    """The parts the relay reads until a target passes its checks (then it asks the gate and the sender)."""

    def __init__(self) -> None:
        events = EventLog()
        self.landing = LandingTargetFeed(events)
        self.telemetry = TelemetryManager(None)
        self.telemetry.apply({"rel_alt_m": 10.0, "roll_deg": 0.0, "pitch_deg": 0.0, "yaw_deg": 0.0, "t_mono_ns": 1})
        self.camera = ActiveCamera(CameraConfig(), events, lambda coro, name: None)
        self.camera.model = CameraModel.from_hfov(640, 480, 62.0)

    @property
    def stopped(self) -> list[str]:
        """Why ``precland`` was turned off ([] while it was not)."""
        return [self.landing.stop_reason] if self.landing.stop_reason else []

    def relay(self) -> LandingTargetRelay:
        return LandingTargetRelay(self.landing, self.telemetry, self.camera, None, None)  # type: ignore[arg-type]


def _frame(seq: int, target: LandingTarget | None = None, status: str = "") -> ProcessedFrame:
    frame = Frame(np.zeros((4, 4, 3), np.uint8), seq, time.monotonic_ns(), time.time_ns())
    return ProcessedFrame(frame, FrameOutcome(0, 0, outputs=FrameOutputs(landing_target=target,
                                                                         landing_status=status)))


def _too_far(seq: int) -> LandingTarget:
    return LandingTarget((0.0, 0.0, 1.0), 5000.0, seq)


def test_a_refused_target_is_not_seen_and_precland_says_why() -> None:
    core = _Core()
    assert core.relay().consider(_frame(1, _too_far(1))) == "refused: distance 5000.0 m puts the pad 5000.0 m " \
                                                          "below the camera, but the vehicle is 10.0 m above home"
    assert core.landing.last_seen_ns is None and core.landing.refusals.refused == 1
    with pytest.raises(UavError, match=r"has not seen a landing target yet \(refused: distance 5000.0 m"):
        core.landing.check_fresh()
    core.relay().consider(_frame(2, None, "marker 7 not in view"))
    assert core.landing.why_none == "the processor says: marker 7 not in view"  # the newest reason


def test_the_processors_own_reason_for_no_target_is_what_precland_says() -> None:
    core = _Core()
    core.relay().consider(_frame(1, None, "2 markers with id 7: which is the pad? no target"))
    assert core.landing.why_none == "the processor says: 2 markers with id 7: which is the pad? no target"
    with pytest.raises(UavError, match=r"yet \(the processor says: 2 markers with id 7: which is the pad\? no"):
        core.landing.check_fresh()


def test_a_run_of_refusals_turns_precland_off_and_says_the_autopilot_lands_on_its_own() -> None:
    core = _Core()
    core.landing.engage()
    for seq in range(1, REFUSALS_TO_STOP):
        core.relay().consider(_frame(seq, _too_far(seq)))
    assert core.landing.engaged and not core.stopped
    behind = LandingTarget((0.0, 0.0, 1.0), 10.0, REFUSALS_TO_STOP)
    object.__setattr__(behind, "direction", (0.0, 0.0, -1.0))
    core.relay().consider(_frame(REFUSALS_TO_STOP, behind))
    assert not core.landing.engaged
    assert core.stopped == [f"{REFUSALS_TO_STOP} landing targets in a row refused, the last: landing target direction "
                            "(0.0, 0.0, -1.0) must be 3 finite numbers with z > 0 (camera frame: x right, y down, "
                            "z ahead); the autopilot's own landing goes on without them"]


def test_a_vehicle_position_of_inf_reaches_no_consumer() -> None:
    core = _Core()
    core.telemetry.apply({"rel_alt_m": math.inf, "north_m": math.inf, "t_mono_ns": 2})
    judged = core.relay().consider(_frame(1, LandingTarget((0.0, 0.0, 1.0), 10.0, 1)))
    assert judged == "refused: no height at the capture to check the distance against"
    assert core.telemetry.snapshot().north_m is None
