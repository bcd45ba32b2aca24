"""The processor's landing targets on the core: when the pad was last seen, and whether ``precland`` is on.

``precland`` is refused unless the processor reports a landing target (``getLandingTarget``) and saw the pad
within :data:`FRESH_TARGET_S`: an autopilot told to land precisely without a target lands where it is
(ArduPilot) or searches for one (PX4). Once it is on, any other vehicle command, a processor fault or a lost
link turns it off again.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from uav_tui.errors import UavError

FRESH_TARGET_S = 1.0
"""``precland`` needs a landing target seen this recently (ArduPilot drops a target older than a second)."""


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

    def seen(self, capture_ns: int) -> None:
        """The processor saw the pad in the frame captured at ``capture_ns``."""
        if self.last_seen_ns is None or capture_ns > self.last_seen_ns:
            self.last_seen_ns = capture_ns

    def check_fresh(self) -> None:
        """Raise UavError saying so unless the pad was seen within :data:`FRESH_TARGET_S`."""
        if self.last_seen_ns is None:
            raise UavError("precland: the processor has not seen a landing target yet: bring the pad into view "
                           "(or use land)")
        age_s = (self.clock() - self.last_seen_ns) / 1e9
        if age_s > FRESH_TARGET_S:
            raise UavError(f"precland: no landing target in the last {FRESH_TARGET_S:g} s (the last one "
                           f"{age_s:.1f} s ago): bring the pad into view (or use land)")

    def engage(self) -> None:
        self.engaged, self.stop_reason = True, ""

    def release(self, reason: str) -> bool:
        """Turn ``precland`` off for ``reason``; True if it was on."""
        was, self.engaged = self.engaged, False
        if was:
            self.stop_reason = reason
        return was
