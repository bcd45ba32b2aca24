"""The event log: operator commands, autonomy decisions, warnings and errors, in order."""

from __future__ import annotations

import asyncio
import logging
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

from uav_tui.output.text import safe, shorten

logger = logging.getLogger(__name__)

MAX_MESSAGE_CHARS = 4000
"""Longer event messages are cut (a processor's exception may carry megabytes)."""

Level = Literal["info", "warning", "error"]
Kind = Literal["command", "autonomy", "processor", "source", "link", "recorder", "web", "platform"]


@dataclass(frozen=True, slots=True)
class Event:
    """Something an operator should be able to see, and read again in events.csv."""

    t_wall_ns: int
    t_mono_ns: int
    level: Level
    kind: Kind
    message: str
    origin: str = "platform"
    """Who caused it: ``tui``, ``script``, ``web``, ``mavlink``, ``platform`` ..."""
    command: str = ""
    """The operator command this event is the outcome or the error of (empty for other events)."""
    autonomy: bool | None = None
    """The autonomy switch this event records: True switched on, False off; None for other events."""


class EventLog:
    """Keeps the recent events and tells listeners, always on the event loop.

    ``emit`` may be called from any thread; listeners run on the loop thread in emission order.
    """

    def __init__(self, keep: int = 500) -> None:
        self.recent: deque[Event] = deque(maxlen=keep)
        self._listeners: list[Callable[[Event], None]] = []
        self._holders: list[Callable[[], None]] = []
        self._loop: asyncio.AbstractEventLoop | None = None
        self._loop_thread: int | None = None

    def bind(self, loop: asyncio.AbstractEventLoop) -> None:
        """Deliver events on ``loop`` from now on."""
        self._loop, self._loop_thread = loop, threading.get_ident()

    def add_holder(self, emit_held: Callable[[], None]) -> None:
        """``emit_held()`` emits what a source of events holds back (a pipe's unread lines, a flood's count):
        :meth:`emit_held` calls it."""
        self._holders.append(emit_held)

    def remove_holder(self, emit_held: Callable[[], None]) -> None:
        if emit_held in self._holders:
            self._holders.remove(emit_held)

    def emit_held(self) -> None:
        """Have every source emit what it holds back now: before a record of the events closes. On the loop."""
        for emit_held in tuple(self._holders):
            emit_held()

    def add_listener(self, listener: Callable[[Event], None]) -> None:
        self._listeners.append(listener)

    def remove_listener(self, listener: Callable[[Event], None]) -> None:
        if listener in self._listeners:
            self._listeners.remove(listener)

    def emit(self, level: Level, kind: Kind, message: str, origin: str = "platform", *, command: str = "",
             t_mono_ns: int | None = None, autonomy: bool | None = None) -> Event:
        """Record and deliver an event; ``message``, ``origin`` and ``command`` are bounded, redacted and escaped here.

        ``t_mono_ns``: when it happened, if that was before now (the wall time is moved back with it).
        ``autonomy``: the event switched autonomy on (True) or off (False).
        """
        message = safe(shorten(message, MAX_MESSAGE_CHARS), multiline=True)
        t_mono, t_wall = time.monotonic_ns(), time.time_ns()
        if t_mono_ns is not None:
            t_mono, t_wall = t_mono_ns, t_wall - (t_mono - t_mono_ns)
        event = Event(t_wall, t_mono, level, kind, message, safe(shorten(origin, 200)),
                      safe(shorten(command, MAX_MESSAGE_CHARS)), autonomy)
        logger.debug("[%s/%s/%s] %s", level, kind, origin, message)  # interfaces show events; logs keep them
        loop = self._loop
        if loop is None or threading.get_ident() == self._loop_thread:
            self._deliver(event)
        elif not loop.is_closed():
            loop.call_soon_threadsafe(self._deliver, event)
        return event

    def _deliver(self, event: Event) -> None:
        self.recent.append(event)
        for listener in tuple(self._listeners):
            try:
                listener(event)
            except Exception:  # a broken listener must not silence the others
                logger.exception("event listener %r failed", listener)


class Repeats:
    """Says a message once, then counts while it repeats (processor exceptions, rejected vectors).

    ``report(key, message)`` emits ``message`` when ``key`` differs from the previous one; the same
    key again is only counted, and how often it repeated is said when a different key comes.
    """

    def __init__(self, events: EventLog, level: Level, kind: Kind, origin: str = "platform") -> None:
        self.events, self.level, self.kind, self.origin = events, level, kind, origin
        self.key: str | None = None
        self.repeats = 0
        """How often ``key`` came again since it was said."""

    def report(self, key: str, message: str) -> None:
        if key == self.key:
            self.repeats += 1
            return
        if self.repeats:
            self.events.emit(self.level, self.kind, f"the previous message repeated {self.repeats} more times "
                             f"({self.key})", self.origin)
        self.key, self.repeats = key, 0
        self.events.emit(self.level, self.kind, message, self.origin)
