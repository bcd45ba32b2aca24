"""A processor's exceptions in a live run: each kind said in full once, then counted.

A processor that raises on every frame must not print a traceback a frame (90 a second buried the
event log and the terminal): the first exception of a kind (the method, the exception's type and the
line that raised it) is said with its traceback; the same kind again is counted, and the count said
every :data:`SUMMARY_S` (``photo_processing raised ValueError 57 more times in 5 s``), as printed
lines are (:mod:`uav_tui.output.line_budget`).
"""

from __future__ import annotations

import asyncio
import re
import time
from dataclasses import dataclass

from uav_tui.events import EventLog

SUMMARY_S = 5.0
"""How often the counts are said."""
MAX_KINDS = 64
"""Kinds followed at once; the exceptions of any more are counted together, never said in full."""

_FRAME = re.compile(r'^  File "(?P<file>.*)", line (?P<line>\d+), in (?P<function>.*)$', re.MULTILINE)
_TYPE = re.compile(r"[A-Za-z_][\w.]*")
_OTHER = ("other",)
"""The key of the exceptions beyond :data:`MAX_KINDS` kinds."""


@dataclass(slots=True)
class _Kind:
    """One kind of exception: what raised it, and how often since its count was last said."""

    method: str
    type_name: str
    since: float
    """When (monotonic s) it was last said in full or counted aloud."""
    count: int = 0
    last: str = ""
    """The newest one's exception line (its message changes: ``bad frame 150``)."""


class ProcessorErrors:
    """Says a processor's exceptions as events (``error``, ``processor``) on the event loop: a kind's first in full,
    the rest in a count every :data:`SUMMARY_S`. A kind that did not come back for a whole period is forgotten,
    and said in full again if it ever does. Keeps the newest one's last line (:attr:`last`).
    """

    def __init__(self, events: EventLog, period_s: float = SUMMARY_S) -> None:
        self.events = events
        self.period_s = period_s
        self.last: str | None = None
        """The newest exception's last line (or why the processor's process died); None: none since the start or
        the last reload."""
        self._kinds: dict[tuple[str, ...], _Kind] = {}
        self._summary: asyncio.TimerHandle | None = None

    def report(self, traceback_text: str, exception: str, frame_seq: int) -> None:
        """One frame's exception: ``traceback_text`` as formatted, ``exception`` its last line (cut)."""
        self.last = exception
        frames = _FRAME.findall(traceback_text)
        method = frames[1][2] if len(frames) > 1 else frames[0][2] if frames else "the processor"
        type_name = match.group() if (match := _TYPE.match(exception)) else "an exception"
        where = frames[-1][:2] if frames else ()
        now, key = time.monotonic(), (method, type_name, *where)
        kind = self._kinds.get(key)
        if kind is None and len(self._kinds) >= MAX_KINDS:
            kind = self._kinds.setdefault(_OTHER, _Kind("the processor", "other exceptions", now))
        if kind is None:
            self._kinds[key] = _Kind(method, type_name, now)
            self.events.emit("error", "processor", f"frame {frame_seq}: {traceback_text.strip()}")
        else:
            kind.count += 1
            kind.last = exception
        self._arm()

    def flush(self) -> None:
        """Say every count now (the run ends)."""
        if self._summary is not None:
            self._summary.cancel()
            self._summary = None
        self._say_counts(time.monotonic())

    def _arm(self) -> None:
        if self._summary is None:
            self._summary = asyncio.get_running_loop().call_later(self.period_s, self._tick)

    def _tick(self) -> None:
        self._summary = None
        now = time.monotonic()
        quiet = [key for key, kind in self._kinds.items() if not kind.count and now - kind.since >= self.period_s]
        for key in quiet:
            del self._kinds[key]
        self._say_counts(now)
        if self._kinds:
            self._arm()

    def _say_counts(self, now: float) -> None:
        for kind in self._kinds.values():
            if kind.count:
                self.events.emit("error", "processor", f"{kind.method} raised {kind.type_name} {kind.count} more "
                                 f"times in {now - kind.since:.0f} s (the last: {kind.last})")
                kind.count, kind.since = 0, now
