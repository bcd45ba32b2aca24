"""The processor's landing targets on the core: when the pad was last seen, whether ``precland`` is on, and the
sending of each target to the autopilot (LANDING_TARGET, converted by the controller).

``precland`` is refused unless the processor reports a landing target (``getLandingTarget``) and saw the pad
within :data:`FRESH_TARGET_S`: an autopilot told to land precisely without a target lands where it is
(ArduPilot) or searches for one (PX4). Once it is on, any other vehicle command, a processor fault, a lost
link, the vehicle leaving its precision-landing mode (a pilot's switch, a failsafe), or a run of
:data:`~uav_tui.flight.plausibility.REFUSALS_TO_STOP` landing targets that cannot be true
(:mod:`uav_tui.flight.plausibility`) turns it off again; the autopilot's own landing then goes on without them.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol

from controllers.base import PrecisionLanding
from controllers.landing_target import LandingTargetFix
from uav_tui.errors import UavError
from uav_tui.flight.autonomy import WATCHDOG_PERIOD_S
from uav_tui.flight.plausibility import LandingCheck, RefusalRun
from uav_tui.flight.relay import SEND_TIMEOUT_S, OneAtATime, not_now

if TYPE_CHECKING:
    from controllers.base import FlightController, LandingTargets, Telemetry
    from sources.camera_model import CameraModel
    from uav_tui.config import Config
    from uav_tui.events import EventLog
    from uav_tui.flight.autonomy import AutonomyGate
    from uav_tui.flight.telemetry import TelemetryManager
    from uav_tui.hosting.host import ProcessedFrame, ProcessorHost
    from uav_values.landing_target import LandingTarget

FRESH_TARGET_S = 1.0
"""``precland`` needs a landing target seen this recently (ArduPilot drops a target older than a second)."""

MODE_REPORTED_WITHIN_S = 3.0
"""After ``precland`` the vehicle must report its precision-landing mode this soon (PX4 says its mode once a
second; a pilot's switch made as ``precland`` was sent would otherwise go unseen)."""


class LandingTargetFeed:
    """When the newest landing target was seen, and the operator's ``precland`` switch.

    Args:
        clock: monotonic nanoseconds, the clock frames are stamped with.
    """

    def __init__(self, clock: Callable[[], int] = time.monotonic_ns) -> None:
        self.clock = clock
        self.engaged = False
        """``precland`` is on: the landing targets are sent to the autopilot."""
        self.stop_reason = ""
        """Why ``precland`` was turned off last ("" while on, or before it was ever on)."""
        self.last_seen_ns: int | None = None
        """Capture time (monotonic ns) of the newest frame the processor saw the pad in."""
        self.engaged_ns = 0
        """When ``precland`` was last turned on (monotonic ns)."""
        self.mode_reported = False
        """The vehicle has reported its precision-landing mode since ``precland`` was turned on."""
        self.check = LandingCheck()
        """Judges each target before it counts as seen or is sent."""
        self.refusals = RefusalRun()
        """The targets that could not be true: how many, the last reason, how many in a row."""
        self.why_none = ""
        """Why the newest frame gave no target to send: ``refused: ...`` (:attr:`check`) or ``the processor says:
        ...`` (its ``status``, :mod:`processors.outputs`); "" after a target passed the checks."""

    def seen(self, capture_ns: int) -> None:
        """The processor saw the pad in the frame captured at ``capture_ns``."""
        if self.last_seen_ns is None or capture_ns > self.last_seen_ns:
            self.last_seen_ns = capture_ns

    def check_fresh(self) -> None:
        """Raise UavError saying so unless the pad was seen within :data:`FRESH_TARGET_S`."""
        if self.last_seen_ns is None:
            why = f" ({self.why_none})" if self.why_none else ""
            raise UavError(f"precland: the processor has not seen a landing target yet{why}: bring the pad into "
                           "view (or use land)")
        age_s = (self.clock() - self.last_seen_ns) / 1e9
        if age_s > FRESH_TARGET_S:
            raise UavError(f"precland: no landing target in the last {FRESH_TARGET_S:g} s (the last one "
                           f"{age_s:.1f} s ago): bring the pad into view (or use land)")

    def engage(self) -> None:
        self.engaged, self.stop_reason = True, ""
        self.engaged_ns, self.mode_reported = self.clock(), False

    def left_mode(self, mode: str | None, landing_modes: frozenset[str]) -> str:
        """Why ``precland`` must end, the vehicle reporting ``mode`` (None: not known), or "" while it lands in one
        of ``landing_modes``: once it reported one of them, any other mode is someone else's choice (a pilot, a
        failsafe), and it must report one within :data:`MODE_REPORTED_WITHIN_S`."""
        wanted = "/".join(sorted(landing_modes))
        if mode in landing_modes:
            self.mode_reported = True
            return ""
        if self.mode_reported and mode is not None:
            return f"the vehicle left {wanted} for {mode}: a pilot, a mission or a failsafe took it"
        waited_s = (self.clock() - self.engaged_ns) / 1e9
        if not self.mode_reported and waited_s > MODE_REPORTED_WITHIN_S:
            return (f"the vehicle did not report {wanted} within {MODE_REPORTED_WITHIN_S:g} s of precland "
                    f"(it reports {mode or 'no mode'})")
        return ""

    def release(self, reason: str) -> bool:
        """Turn ``precland`` off for ``reason``; True if it was on."""
        was, self.engaged = self.engaged, False
        if was:
            self.stop_reason = reason
        return was


def say_precland_end(events: EventLog, reason: str, landed_with: int | None) -> None:
    """``precland`` was turned off for ``reason``: a warning, or, ``landed_with`` N landing targets sent, the landing's
    normal end (the vehicle landed and disarmed)."""
    if landed_with is None:
        events.emit("warning", "autonomy", f"precland off, landing targets no longer sent: {reason}")
    else:
        events.emit("info", "autonomy", f"precland done: {reason} ({landed_with} landing targets sent)")


def landing_fix(target: LandingTarget, capture_ns: int, camera: CameraModel, at_capture: Telemetry) -> LandingTargetFix:
    """The fix the controller converts for its autopilot: ``target`` with the camera's mounting and the vehicle's
    attitude and position at the frame's capture (None where the telemetry had none)."""
    t = at_capture
    attitude = (t.roll_deg, t.pitch_deg, t.yaw_deg)
    position = (t.north_m, t.east_m, t.down_m)
    return LandingTargetFix(
        capture_ns, target.direction, target.distance_m, camera.rotation_body_camera, camera.mount.offset_m,
        None if None in attitude else attitude,  # type: ignore[arg-type]
        None if None in position else position)  # type: ignore[arg-type]


class LandingTargetSender(OneAtATime):
    """Sends one landing target at a time to the controller (:class:`~uav_tui.flight.relay.OneAtATime`).

    Args:
        controller: the flight controller (a :class:`~controllers.base.LandingTargets`).
        events: the core's event log.
        timeout_s: the longest one send may take.
    """

    def __init__(self, controller: LandingTargets, events: EventLog, timeout_s: float = SEND_TIMEOUT_S) -> None:
        super().__init__(events, "landing target", timeout_s)
        self.controller = controller

    def send(self, fix: LandingTargetFix) -> None:
        """Start sending ``fix`` (on the loop); the caller checked :attr:`busy`."""
        self.start(lambda: self.controller.send_landing_target(fix))


class LandingCore(Protocol):
    """What the landing-target relay reads of the core, and how it stops ``precland``."""

    config: Config
    telemetry: TelemetryManager
    gate: AutonomyGate
    landing: LandingTargetFeed
    landing_sender: LandingTargetSender | None

    @property
    def camera(self) -> CameraModel | None: ...

    @property
    def controller(self) -> FlightController | None: ...

    @property
    def worker(self) -> ProcessorHost | None: ...

    def newest_frame_age(self) -> float | None: ...

    def stop_precland(self, reason: str, *, landed: bool = False) -> None: ...


def consider_landing_target(core: LandingCore, result: ProcessedFrame) -> None:
    """Judge the frame's landing target (:class:`~uav_tui.flight.plausibility.LandingCheck`), then send it while
    ``precland`` or autonomy is on, the frame fresh and the link alive; ``result.landing`` says what was done
    (frames.csv). A run of refusals turns ``precland`` off."""
    target = result.outputs.landing_target
    landing = core.landing
    if target is None:
        status = result.outputs.landing_status
        landing.why_none = f"the processor says: {status}" if status else ""  # not an older frame's reason
        return
    if core.camera is None:
        result.landing = "not sent: no camera model to check it against"
        landing.why_none = "no camera model to check the target against (set camera_hfov or a calibration file)"
        return
    capture_ns = result.frame.t_mono_ns
    at_capture = core.telemetry.at(capture_ns)[0]
    judged = landing.check.judge(target, result.frame.seq, capture_ns, core.camera, at_capture)
    if judged.target is None:
        result.landing = landing.why_none = f"refused: {judged.reason}"
        if landing.refusals.refuse(judged.reason) and landing.engaged:
            core.stop_precland(f"{landing.refusals.in_a_row} landing targets in a row refused, the last: "
                               f"{judged.reason}; the autopilot's own landing goes on without them")
        return
    landing.refusals.accept()
    landing.why_none = ""
    landing.seen(capture_ns)
    why = _blocked(core, capture_ns)
    result.landing = f"not sent: {why}" if why else "sent"
    if why:
        return
    assert core.landing_sender is not None
    core.landing_sender.send(landing_fix(judged.target, capture_ns, core.camera, at_capture))

def _blocked(core: LandingCore, capture_ns: int) -> str:
    """Why a landing target seen in the frame captured at ``capture_ns`` is not sent now, or ""."""
    if not (core.landing.engaged or core.gate.enabled):
        return "precland and autonomy off"
    if core.landing_sender is None or core.controller is None:
        return "the flight controller takes no landing targets"
    return not_now(core.controller, core.config.safety, (core.gate.clock() - capture_ns) / 1e9, core.landing_sender)

async def watch_precland(core: LandingCore) -> None:
    """Turn ``precland`` off on the faults that stop autonomy, once the vehicle landed and disarmed, and when it
    leaves its precision-landing mode (:meth:`LandingTargetFeed.left_mode`)."""
    worker = core.worker
    assert worker is not None
    while True:
        await asyncio.sleep(WATCHDOG_PERIOD_S)
        if not core.landing.engaged:
            continue
        fault = core.gate.fault(core.newest_frame_age(), worker.busy_s, worker.consecutive_errors)
        snapshot = core.telemetry.snapshot()
        if not fault and snapshot.armed is False:
            core.stop_precland("landed and disarmed", landed=True)
            continue
        if not fault and isinstance(core.controller, PrecisionLanding):
            fault = core.landing.left_mode(snapshot.flight_mode, core.controller.landing_modes)
        if fault:
            core.stop_precland(fault)
