"""The operator's ``precland`` switch and when the pad was last seen (the core's :class:`LandingTargetFeed`).

``precland`` is refused unless the processor reports a landing target (``getLandingTarget``) and saw the pad
within :data:`FRESH_TARGET_S`: an autopilot told to land precisely without a target lands where it is
(ArduPilot) or searches for one (PX4). Once it is on, any other vehicle command, a processor fault, a lost
link, the vehicle leaving its precision-landing mode (a pilot's switch, a failsafe), or a run of
:data:`~uav_tui.flight.plausibility.REFUSALS_TO_STOP` landing targets that cannot be true
(:mod:`uav_tui.flight.plausibility`) turns it off again; the autopilot's own landing then goes on without them.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from uav_tui.errors import UavError
from uav_tui.flight.plausibility import LandingCheck, RefusalRun

if TYPE_CHECKING:
    from uav_tui.events import EventLog

FRESH_TARGET_S = 1.0
"""``precland`` needs a landing target seen this recently (ArduPilot drops a target older than a second)."""

MODE_REPORTED_WITHIN_S = 3.0
"""After ``precland`` the vehicle must report its precision-landing mode this soon (PX4 says its mode once a
second; a pilot's switch made as ``precland`` was sent would otherwise go unseen)."""


class LandingTargetFeed:
    """When the newest landing target was seen, and the operator's ``precland`` switch.

    Args:
        events: where the switch's end is said (:meth:`end`).
        clock: monotonic nanoseconds, the clock frames are stamped with.
    """

    def __init__(self, events: EventLog, clock: Callable[[], int] = time.monotonic_ns) -> None:
        self.events = events
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

    def end(self, reason: str, landed_with: int | None = None) -> None:
        """Turn ``precland`` off for ``reason`` (a fault, another command) and say so when it was on: a warning, or,
        ``landed_with`` N landing targets sent, the landing's normal end (the vehicle landed and disarmed)."""
        if not self.release(reason):
            return
        if landed_with is None:
            self.events.emit("warning", "autonomy", f"precland off, landing targets no longer sent: {reason}")
        else:
            self.events.emit("info", "autonomy", f"precland done: {reason} ({landed_with} landing targets sent)")
