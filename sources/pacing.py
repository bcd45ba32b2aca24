"""Frame pacing shared by the sources that generate or replay frames at a fixed rate."""

from __future__ import annotations

import threading
import time


class Pacer:
    """Sleeps until the next frame is due at ``fps``; never bursts to catch up after a delay.

    ``wait`` returns False if ``stop`` was set while waiting.
    """

    def __init__(self, fps: float, stop: threading.Event) -> None:
        self.period_ns = int(1e9 / fps) if fps > 0 else 0
        self._stop = stop
        self._next_ns = time.monotonic_ns()

    def wait(self) -> bool:
        if self.period_ns == 0:
            return not self._stop.is_set()
        now = time.monotonic_ns()
        if self._next_ns > now and self._stop.wait((self._next_ns - now) / 1e9):
            return False
        # Late by more than one period (a slow reader, a suspended process): restart the schedule.
        self._next_ns = max(self._next_ns, time.monotonic_ns() - self.period_ns) + self.period_ns
        return not self._stop.is_set()
