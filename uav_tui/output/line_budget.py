"""Lines from outside shown at a bounded rate: a burst at once, then a few a second, and a count of the rest.

A decoder complaining of every damaged block, or a processor that prints on every frame, must not
bury what the operator needs to read (nor cost the loop a line each).
"""

from __future__ import annotations

import asyncio
import math
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any, Generic, TypeVar

BURST_LINES = 20
"""Lines shown at once before the rate applies."""
LINES_PER_S = 1.0
"""Lines a second shown in a flood; the others are counted and the count is said."""

T = TypeVar("T")
S = TypeVar("S", str, bytes)


class LineBudget(Generic[T]):
    """Passes lines to ``say_line`` within the budget and says how many it left out with ``say_left_out``.

    The count is said before the next line that fits, or ``1 / per_s`` seconds after the first line left
    out, or at :meth:`close`. Create it on the event loop's thread (its timer says the count there); lines may
    come from any thread, and the callbacks are called on the thread that gave the line (the timer's on the loop).
    """

    def __init__(self, say_line: Callable[[T], object], say_left_out: Callable[[int], object], *,
                 burst: int = BURST_LINES, per_s: float = LINES_PER_S) -> None:
        self._say_line = say_line
        self._say_left_out = say_left_out
        self._burst = burst
        self._per_s = per_s
        self._tokens = float(burst)
        self._refilled = time.monotonic()
        self.left_out = 0
        """Lines not shown and not yet counted aloud."""
        self._lock = threading.Lock()
        self._loop = asyncio.get_running_loop()
        self._count_due: asyncio.TimerHandle | None = None
        self._arming = False
        """A thread asked the loop to start the count's timer."""
        self._closed = False
        self._said_at = -math.inf
        """When (monotonic s) a count was last said: the timer says none sooner than ``1 / per_s`` after it."""

    def line(self, text: T) -> None:
        self.lines((text,))

    def lines(self, lines: Sequence[T]) -> None:
        """Pass on the first of ``lines`` that fit the budget, count the others: a flood costs no more than its
        length (nothing is done with a line left out)."""
        with self._lock:
            shown = self._take(len(lines))
            counted = self._take_count() if shown else 0
            self.left_out += len(lines) - shown
            arm = self.left_out > 0 and self._count_due is None and not self._arming
            self._arming = self._arming or arm
        if counted:
            self._say_left_out(counted)
        for text in lines[:shown]:
            self._say_line(text)
        if arm:
            self._loop.call_soon_threadsafe(self._arm)

    def say_count(self) -> None:
        """Say the count of what was left out so far now (a record of the lines is about to close)."""
        with self._lock:
            counted = self._take_count()
        if counted:
            self._say_left_out(counted)

    def close(self) -> None:
        """Say the count now; no count is said after this. Call it on the loop."""
        with self._lock:
            self._closed = True
            counted = self._take_count()
            if self._count_due is not None:
                self._count_due.cancel()
                self._count_due = None
        if counted:
            self._say_left_out(counted)

    def _take(self, count: int) -> int:
        """How many of ``count`` lines fit now (they are taken)."""
        now = time.monotonic()
        self._tokens = min(self._burst, self._tokens + (now - self._refilled) * self._per_s)
        self._refilled = now
        taken = min(count, int(self._tokens))
        self._tokens -= taken
        return taken

    def _take_count(self) -> int:
        """The count to say now (it is then zero). It takes no share of the budget: a steady stream at the rate would
        starve it, and it comes at most once per line shown or per ``1 / per_s`` seconds anyway. A timer armed for
        it is left to fire (it may have been armed by another thread) and says what was left out since, if anything.
        """
        counted, self.left_out = self.left_out, 0
        if counted:
            self._said_at = time.monotonic()
        return counted

    def _arm(self) -> None:
        """On the loop: say the count ``1 / per_s`` seconds from now (if it was not said meanwhile)."""
        with self._lock:
            self._arming = False
            if self.left_out and self._count_due is None and not self._closed:
                self._count_due = self._loop.call_later(1 / self._per_s, self._count)

    def _count(self) -> None:
        with self._lock:
            self._count_due = None
            wait = self._said_at + 1 / self._per_s - time.monotonic()
            if self._closed or wait > 0:  # a line said a count meanwhile: the next one is said a period after it
                if self.left_out and not self._closed:
                    self._count_due = self._loop.call_later(wait, self._count)
                return
            counted = self._take_count()
        if counted:
            self._say_left_out(counted)


class LineSplitter(Generic[S]):
    """Cuts a stream of text (``str``, or ``bytes`` read from a pipe) into lines at ``\n`` only (a ``\r`` is part
    of its line); a line that reaches ``max_line`` without ending is given as it is, and the rest of it as the lines
    that follow. Not thread-safe.
    """

    def __init__(self, newline: S, max_line: int) -> None:
        self._newline: S = newline
        self._max_line = max_line
        self._pieces: list[S] = []
        """The unfinished line's pieces (joined only when it ends: a write at a time would copy it each time)."""
        self._chars = 0

    def feed(self, text: S) -> list[S]:
        """The lines ``text`` finishes, without their ``\n``."""
        if self._newline not in text and self._chars + len(text) < self._max_line:
            self._pieces.append(text)
            self._chars += len(text)
            return []
        lines: list[S] = (self._newline[:0].join(self._pieces) + text).split(self._newline)
        rest = lines.pop()
        if len(rest) >= self._max_line:
            lines.append(rest)
            rest = self._newline[:0]
        self._pieces, self._chars = [rest], len(rest)
        return lines

    def rest(self) -> S:
        """The unfinished line, taken (at the stream's end)."""
        rest = self._newline[:0].join(self._pieces)
        self._pieces, self._chars = [], 0
        return rest


class BudgetedText:
    """A stand-in for ``sys.stdout`` (any thread): what is written is cut into lines by a :class:`LineSplitter`,
    none longer than ``max_line`` characters, and passed to ``say_line`` within a :class:`LineBudget`; the count of
    the rest goes to ``say_left_out``. Create it on the event loop.

    Other file attributes (``encoding``, ``isatty``) are those of ``file``.
    """

    def __init__(self, file: Any, say_line: Callable[[str], object], say_left_out: Callable[[int], None], *,
                 max_line: int = 64 * 1024) -> None:
        self._file = file
        self._budget: LineBudget[str] = LineBudget(say_line, say_left_out)
        self._lines = LineSplitter("\n", max_line)
        self._lock = threading.Lock()

    def write(self, text: str) -> int:
        with self._lock:
            lines = self._lines.feed(text)
        if lines:
            self._budget.lines(lines)
        return len(text)

    def flush(self) -> None:
        """Nothing to do: lines are passed on as they end."""

    def say_count(self) -> None:
        """Say the count of what was left out so far now. On the loop."""
        self._budget.say_count()

    def close(self) -> None:
        """Pass on the unfinished line and say the count. On the loop."""
        with self._lock:
            rest = self._lines.rest()
        if rest:
            self._budget.line(rest)
        self._budget.close()

    def __getattr__(self, name: str) -> Any:
        return getattr(self._file, name)
