"""Lines from outside shown at a bounded rate: a burst at once, then a few a second, and a count of the rest.

A decoder complaining of every damaged block, or a processor that prints on every frame, must not
bury what the operator needs to read (nor cost the loop a line each).
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable

BURST_LINES = 20
"""Lines shown at once before the rate applies."""
LINES_PER_S = 1.0
"""Lines a second shown in a flood; the others are counted and the count is said."""


class LineBudget:
    """Passes lines to ``say_line`` within the budget and says how many it left out with ``say_left_out``.

    The count is said before the next line that fits, or ``1 / per_s`` seconds after the first line left
    out, or at :meth:`close`. Call it on the event loop's thread.
    """

    def __init__(self, say_line: Callable[[str], None], say_left_out: Callable[[int], None], *,
                 burst: int = BURST_LINES, per_s: float = LINES_PER_S) -> None:
        self._say_line = say_line
        self._say_left_out = say_left_out
        self._burst = burst
        self._per_s = per_s
        self._tokens = float(burst)
        self._refilled = time.monotonic()
        self.left_out = 0
        """Lines not shown and not yet counted aloud."""
        self._count_due: asyncio.TimerHandle | None = None

    def line(self, text: str) -> None:
        if not self._take():
            self.left_out += 1
            if self._count_due is None:
                self._count_due = asyncio.get_running_loop().call_later(1 / self._per_s, self._count)
            return
        self._count()
        self._say_line(text)

    def close(self) -> None:
        """Say the count now."""
        self._count()

    def _take(self) -> bool:
        now = time.monotonic()
        self._tokens = min(self._burst, self._tokens + (now - self._refilled) * self._per_s)
        self._refilled = now
        if self._tokens < 1:
            return False
        self._tokens -= 1
        return True

    def _count(self) -> None:
        """Say how many lines were left out. It takes no share of the budget: a steady stream at the rate would
        starve it, and it comes at most once per line shown or per ``1 / per_s`` seconds anyway."""
        if self._count_due is not None:
            self._count_due.cancel()
            self._count_due = None
        if self.left_out:
            self._say_left_out(self.left_out)
            self.left_out = 0
