"""The autonomy gate: the only path from a processor's vector to the flight controller.

It enforces the safety rules of docs/safety.md: vectors are validated and clamped (rule 1), executed
only while autonomy is on, the vehicle is armed and in the air, the link is alive and the frame is
fresh (rule 2), and a watchdog stops autonomy (zero velocity, hold) on a processor stall, repeated
processor errors, a camera stall or link loss (rule 4). Streaming at >= 10 Hz and the final
zero + hold of each vector (rule 3) are the controller's ``set_fly_vector``.
"""

from __future__ import annotations

import asyncio
import enum
import logging
import math
import time
from collections.abc import Callable
from numbers import Real
from typing import Any

from controllers.base import FailsafeCheck, FenceCheck, FlightController, OwnModes, VectorEndKind
from uav_tui.config import Config, EnvelopeConfig, SafetyConfig
from uav_tui.errors import KNOWN_ERRORS, UavError
from uav_tui.events import EventLog, Level, Repeats
from uav_tui.flight.envelope import Breach, Envelope, carry_out, configured_envelope
from uav_tui.flight.fly_back import fly_back
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.output.text import describe

logger = logging.getLogger(__name__)

WATCHDOG_PERIOD_S = 0.1

AUTONOMY_MODES = frozenset({"HOLD", "OFFBOARD"})
"""Flight modes autonomy may fly from unless the controller says otherwise (:func:`own_modes`): the hold
the platform leaves behind and offboard itself. Any other mode means a pilot, a mission or a failsafe has
the vehicle."""


def own_modes(controller: FlightController | None) -> frozenset[str]:
    """The flight modes (MAVSDK's names) the platform's own vectors and holds leave the vehicle in.

    A controller may say (``own_modes``): on ArduCopter the platform holds in GUIDED (OFFBOARD), so
    HOLD there is LOITER or BRAKE, a pilot's or a failsafe's. Otherwise :data:`AUTONOMY_MODES`.
    """
    return controller.own_modes if isinstance(controller, OwnModes) else AUTONOMY_MODES

Vector = tuple[float, float, float]


class Verdict(enum.Enum):
    """What the gate did with a processed frame's vector."""

    EXECUTED = "executed"  # sent to the flight controller (clamped, maybe)
    NOT_EXECUTED = "not executed"  # valid, but a condition of safety rule 2 did not hold
    REJECTED = "rejected"  # not a vector that may fly (safety rule 1)
    NO_VECTOR = "no vector"  # the processor had nothing to do
    ERROR = "error"  # the processor raised on the frame


class Decision(str):
    """A decision's text, as ``frames.csv`` records it and every interface shows it, with its :class:`Verdict`.

    It is the text (compared, shown and written as before); code branches on :attr:`verdict`.
    """

    verdict: Verdict | None
    """None only for :data:`NO_DECISION`."""

    def __new__(cls, verdict: Verdict | None, text: str) -> Decision:
        decision = super().__new__(cls, text)
        decision.verdict = verdict
        return decision

    def __reduce__(self) -> tuple[type[Decision], tuple[Verdict | None, str]]:
        """Copied and pickled with its verdict (``dataclasses.asdict`` deep-copies a status)."""
        return Decision, (self.verdict, str(self))


NO_DECISION = Decision(None, "")
"""Before the first vector is judged."""


class StopCause(enum.Enum):
    """Why the watchdog stops autonomy (safety rule 4); the stop reason's text says the details."""

    PROCESSOR_STALLED = "processor stalled"
    PROCESSOR_FAILING = "processor failing"
    TAKEN_OVER = "taken over"  # a pilot, a mission or a failsafe switched modes: no hold, it has the vehicle
    CAMERA_STALLED = "camera stalled"
    LINK_LOST = "link lost"


def check_vector(raw: Any, safety: SafetyConfig) -> tuple[Vector | None, str]:
    """Validate and clamp a processor's vector.

    Returns ``(vector, note)``: the clamped vector and "" or what was clamped; or ``(None, reason)``
    when it must be rejected (wrong shape or type, NaN/inf or too large for a float, t <= 0). Notes
    describe the value in bounded text, whatever the processor returned.
    """
    if not isinstance(raw, tuple | list) or len(raw) != 3:
        return None, f"rejected: expected (vx, vy, t), got {describe(raw)}"
    if not all(isinstance(v, Real) and not isinstance(v, bool) for v in raw):
        return None, f"rejected: non-numeric vector {describe(raw)}"
    try:
        vx, vy, t = (float(v) for v in raw)
    except OverflowError:  # an int like 10**400 has no float
        return None, f"rejected: vector too large for a float {describe(raw)}"
    if not all(math.isfinite(v) for v in (vx, vy, t)):
        return None, f"rejected: non-finite vector {describe(raw)}"
    if t <= 0:
        return None, f"rejected: duration t={t:g} must be > 0"
    limit = safety.max_speed
    clamped = (max(-limit, min(limit, vx)), max(-limit, min(limit, vy)), min(t, safety.max_t))
    note = "" if clamped == (vx, vy, t) else (f"clamped {_numbers((vx, vy, t))} to {_numbers(clamped)} "
                                              f"(max_speed {limit:g} m/s, max_t {safety.max_t:g} s)")
    return clamped, note


def _numbers(vector: Vector) -> str:
    return "(" + ", ".join(f"{v:.3g}" for v in vector) + ")"


class AutonomyGate:
    """Decides, per processed frame, whether its vector flies; stops autonomy when something fails."""

    def __init__(self, safety: SafetyConfig, telemetry: TelemetryManager, events: EventLog) -> None:
        self.safety = safety
        self.telemetry = telemetry
        self.events = events
        self.controller: FlightController | None = None
        self.envelope = Envelope(EnvelopeConfig(), events)
        """Where, how high and how long vectors may fly (the platform sets the configured one)."""
        self.enabled = False
        self.stop_reason = ""
        """Why autonomy last stopped by itself (shown on every interface)."""
        self.refusal = ""
        """Why autonomy may not be switched on at all (e.g. an autopilot failsafe that is too slow)."""
        self.executed = 0
        self.rejected = 0
        self.last_vector: Vector | None = None
        self.last_decision = NO_DECISION
        self._rejections = Repeats(events, "warning", "autonomy", "processor")
        self._pending: tuple[Vector, ProcessedFrame] | None = None
        self._wake = asyncio.Event()
        self._flown = False
        """A vector was sent since autonomy was last switched on."""
        self._flying_back: asyncio.Task[None] | None = None
        """``lost_action = "last_seen"`` flying the vehicle back (:mod:`.fly_back`), until it holds."""
        self.clock: Callable[[], int] = time.monotonic_ns
        """Monotonic ns that frame ages are measured against (a replay's recorded clock in a replay)."""
        self.stop_listeners: list[Callable[[str], None]] = []
        """Called with the reason each time autonomy is turned off (or told off again, at exit): what else the
        processor drives stops with the vectors (the gimbal)."""

    def bind(self, telemetry: TelemetryManager, controller: FlightController | None, config: Config) -> None:
        """The run's vehicle and its telemetry, once connected, and the configured envelope (ConfigError: it
        cannot be used)."""
        self.telemetry, self.controller = telemetry, controller
        self.envelope = configured_envelope(config, self.events, telemetry)

    async def check_autopilot_failsafe(self) -> None:
        """Read (and set) the autopilot's offboard-loss failsafe and read its fence; autonomy is refused while the
        failsafe is too slow, or without a fence when ``require_autopilot_fence`` is set."""
        problems: list[str] = []
        if isinstance(self.controller, FailsafeCheck):
            report = await self.controller.check_failsafe(self.safety.max_t, tune=self.safety.tune_autopilot_failsafe)
            self.events.emit("info", "autonomy", report.summary())
            problems += report.problems
        if isinstance(self.controller, FenceCheck):
            fence = await self.controller.check_fence()
            self.events.emit("info", "autonomy", fence.summary)
            if not fence.enabled and self.envelope.config.require_autopilot_fence:
                problems.append("the autopilot has no fence that acts (require_autopilot_fence): set one up")
        self.refusal = "; ".join(problems)
        if problems:
            self.events.emit("error", "autonomy", f"autonomy will be refused: {self.refusal}")

    def check_can_enable(self) -> None:
        """Raise UavError saying why autonomy cannot go on (no vehicle, its failsafe too slow)."""
        if self.controller is None:
            raise UavError("autonomy needs a flight controller; start with --fc sim or a connection string")
        if self.refusal or self.envelope.refusal:
            raise UavError(f"autonomy refused: {self.refusal or self.envelope.refusal}")

    def enable(self, origin: str) -> None:
        self.check_can_enable()
        self.stop_flying_back()
        self.envelope.engage()
        if (breach := self._breach()) is not None:
            raise UavError(f"autonomy refused: {breach.reason}")
        self.enabled, self.stop_reason, self._flown = True, "", False
        self.events.emit("info", "autonomy", "autonomy ON", origin, autonomy=True)

    async def disable(self, origin: str, reason: str | None = None, *, hold: bool = True) -> None:
        """Turn autonomy off; with ``hold`` and a vector running, zero it and hold at once.

        ``reason`` is why it stops by itself (shown as :attr:`stop_reason`); None: the operator switched it off.
        """
        was_enabled, self.enabled, self._pending = self.enabled, False, None
        self.stop_flying_back()
        if reason is not None:
            self.stop_reason = reason
        for listener in self.stop_listeners:
            listener(reason or "operator")
        if was_enabled or reason is not None:
            level: Level = "info" if reason is None else "warning"
            self.events.emit(level, "autonomy", f"autonomy OFF: {reason or 'operator'}", origin, autonomy=False)
        if hold and self.controller is not None and self.controller.vector_active:
            try:
                await self.controller.hold()
            except KNOWN_ERRORS as exc:
                self.events.emit("error", "autonomy", f"hold after stopping autonomy failed: {exc}", origin)

    def consider(self, result: ProcessedFrame) -> Decision:
        """Decide on ``result``'s vector (on the loop, right after processing); returns the decision."""
        if self.enabled:
            self.envelope.saw(result.outcome.box is not None or result.outcome.vector is not None,
                              self.telemetry.snapshot())
        if result.outcome.vector is None:
            return Decision(Verdict.ERROR, "error") if result.outcome.error else Decision(Verdict.NO_VECTOR,
                                                                                   "no vector")
        vector, note = check_vector(result.outcome.vector, self.safety)
        key, why_not = note, "" if vector is None else self._why_not(result)
        if vector is not None and not why_not:  # a vector that would fly: within the envelope?
            confined = self.envelope.confine(vector, self.telemetry.snapshot())
            vector, key = confined.vector, confined.key or note
            note = confined.note if vector is None else "; ".join(filter(None, (note, confined.note)))
        if vector is None:
            self.rejected += 1
            self.last_decision = Decision(Verdict.REJECTED, note)
            self.last_vector = None  # no stale vector beside this decision
            self._rejections.report(key, f"frame {result.frame.seq}: vector {note}")
            return self.last_decision
        self.last_vector = vector
        self.last_decision = (Decision(Verdict.NOT_EXECUTED, why_not) if why_not else
                              Decision(Verdict.EXECUTED, "executed" + (f" ({note})" if note else "")))
        if self.last_decision.verdict is Verdict.EXECUTED:
            self._pending = (vector, result)
            self._wake.set()
        return self.last_decision

    def _why_not(self, result: ProcessedFrame) -> str:
        if not self.enabled:
            return "not executed: autonomy off"
        if self.controller is None:
            return "not executed: no flight controller"
        snapshot = self.telemetry.snapshot()
        if not snapshot.armed:
            return "not executed: vehicle not armed"
        if not snapshot.in_air:
            return "not executed: vehicle not in the air"
        if snapshot.flight_mode not in own_modes(self.controller):
            return f"not executed: vehicle in {snapshot.flight_mode} mode"
        age = self.controller.heartbeat_age_s()
        if age >= self.safety.link_timeout:
            return f"not executed: link lost (heartbeat {age:.1f} s old)"
        frame_age_s = (self.clock() - result.frame.t_mono_ns) / 1e9
        if frame_age_s >= self.safety.max_frame_age:
            return f"not executed: frame {frame_age_s:.2f} s old"
        return ""

    async def run(self) -> None:
        """Send accepted vectors to the controller, newest first; until cancelled."""
        while True:
            await self._wake.wait()
            self._wake.clear()
            pending, self._pending = self._pending, None
            if pending is None or not self.enabled or self.controller is None:
                continue
            (vx, vy, t), result = pending
            taken_over = self._taken_over()
            if taken_over:
                await self.disable("autonomy", taken_over, hold=False)
                continue
            if self._why_not(result):  # things changed while it waited for the previous command
                continue
            try:
                await self.controller.set_fly_vector(vx, vy, t, yield_to_others=True)
                self.executed += 1
                self._flown = True
            except KNOWN_ERRORS as exc:
                await self.disable("autonomy", f"vector failed: {exc}")

    def _taken_over(self) -> str:
        """Why autonomy must let go: the vehicle left offboard under a running vector (pilot, failsafe)."""
        assert self.controller is not None
        end = self.controller.last_vector_end
        if self._flown and not self.controller.vector_active and end.kind is VectorEndKind.LEFT_OFFBOARD:
            return f"{end}: the pilot, a mission or a failsafe took over"
        return ""

    async def watch(self, frame_age: Callable[[], float | None], processor_busy_s: Callable[[], float],
                    processor_errors: Callable[[], int]) -> None:
        """Stop autonomy when the processor stalls or keeps failing, the camera stalls or the link is lost."""
        while True:
            await asyncio.sleep(WATCHDOG_PERIOD_S)
            if not self.enabled:
                continue
            failure = self._failure(frame_age(), processor_busy_s(), processor_errors())
            if failure is not None:
                cause, reason = failure
                # Whoever switched modes has the vehicle: a hold from here would override them.
                await self.disable("watchdog", reason, hold=cause is not StopCause.TAKEN_OVER)
            elif (breach := self._breach()) is not None:
                await self._breached(breach)

    def _breach(self) -> Breach | None:
        """A limit of the envelope the vehicle in the air is past (on the ground nothing flies anyway)."""
        snapshot = self.telemetry.snapshot()
        return self.envelope.breach(snapshot) if snapshot.in_air else None

    async def _breached(self, breach: Breach) -> None:
        """A limit of the envelope is past: autonomy off, then the limit's action (hold, RTL, land)."""
        await self.disable("envelope", f"{breach.reason}: {breach.action.upper()}", hold=breach.action == "hold")
        if breach.action == "last_seen" and breach.point is not None and self.controller is not None:
            self._flying_back = asyncio.create_task(fly_back(
                self.controller, self.telemetry, self.envelope, self.events, breach.point,
                max_speed=self.safety.max_speed, link_timeout=self.safety.link_timeout,
                modes=own_modes(self.controller)), name="fly back")
        elif breach.action != "hold" and self.controller is not None:
            try:
                await carry_out(self.controller, breach.action)
            except KNOWN_ERRORS as exc:
                self.events.emit("error", "autonomy", f"{breach.action.upper()} at the envelope failed: {exc}; "
                                 "take over with the remote", "envelope")

    def stop_flying_back(self) -> None:
        """Stop flying back to where the target was last seen (autonomy on again, an operator's command)."""
        if self._flying_back is not None:
            self._flying_back.cancel()
            self._flying_back = None

    def fault(self, frame_age: float | None, busy_s: float, errors: int) -> str:
        """Why whatever the processor drives must stop now (processor stalled or failing, camera stalled, link lost),
        or "" (``precland``'s landing targets stop on the same faults as vectors)."""
        failure = self._failure(frame_age, busy_s, errors)
        return "" if failure is None or failure[0] is StopCause.TAKEN_OVER else failure[1]

    def _failure(self, frame_age: float | None, busy_s: float, errors: int) -> tuple[StopCause, str] | None:
        """Why autonomy must stop now, and the reason to show; None: nothing failed."""
        s = self.safety
        if busy_s > s.max_t:
            return StopCause.PROCESSOR_STALLED, f"processor stalled ({busy_s:.1f} s in one call)"
        if errors >= s.max_processor_errors:
            return StopCause.PROCESSOR_FAILING, f"processor raised {errors} times in a row"
        mode = self.telemetry.snapshot().flight_mode
        if self._flown and mode is not None and mode not in own_modes(self.controller):
            return StopCause.TAKEN_OVER, f"vehicle switched to {mode}: the pilot, a mission or a failsafe took over"
        if self.controller is not None and (taken_over := self._taken_over()):
            return StopCause.TAKEN_OVER, taken_over
        if frame_age is None or frame_age > s.camera_stall:
            return StopCause.CAMERA_STALLED, ("camera stalled" if frame_age is None else
                                              f"camera stalled (newest frame {frame_age:.1f} s old)")
        if self.controller is not None:
            age = self.controller.heartbeat_age_s()
            if age > s.link_timeout:
                return StopCause.LINK_LOST, f"link lost (heartbeat {age:.1f} s old)"
        return None
