"""What native libraries write on file descriptor 2, turned into events.

FFmpeg, OpenCV, libjpeg and libcamera print straight to fd 2: a damaged frame in a lossy RTSP stream
or a USB camera's MJPEG gives ``[h264 @ 0x…] error while decoding MB 12 5`` or ``Corrupt JPEG data``,
many times a second. The dashboard is drawn on that same terminal, so the lines landed in the middle
of the screen; headless, they came unescaped and unbounded between the status lines, a terminal that
stopped taking output made the decoder (and with it the camera) wait, and ``events.csv`` never had
them.

While :func:`native_stderr_as_events` lasts, fd 2 is a pipe that never makes a writer wait (what
does not fit while the loop is busy is lost, not waited for). The event loop reads it as it reads a
socket and emits each line as an event (``native library: …``; escaped, bounded, at most
:class:`~uav_tui.output.line_budget.LineBudget`'s 20 at once and one a second after that, with a count of
what was left out).
Python's own writes to stderr (log records, tracebacks, the dashboard itself) keep going to the
terminal through a duplicate of the old fd 2.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import re
import sys
from collections.abc import Callable, Iterator
from typing import Any

from uav_tui.events import EventLog, Level
from uav_tui.output.line_budget import LineBudget, LineSplitter
from uav_tui.output.text import shorten

LINE_CHARS = 300
"""Longer lines are cut (one that never ends is taken in pieces this long)."""
ORIGIN = "native"
"""The events' origin: interfaces list them without popping them up (a flood would cover the screen)."""
_INFO = re.compile(r"\b(INFO|DEBUG)\b")
"""A line its library marks as information (libcamera's ``INFO Camera …``, OpenCV's ``[ INFO:0@…``)."""


@contextlib.contextmanager
def native_stderr_as_events(events: EventLog) -> Iterator[Callable[[], None]]:
    """While it lasts, lines native code writes on fd 2 are events, not text on the terminal. Use it on the loop.

    Python file objects on fd 2 (``sys.stderr``, ``sys.__stderr__``, logging's stream handlers) are
    pointed at a duplicate of it meanwhile, so they keep writing to the terminal. Gives what emits the
    lines written so far at once (a report that follows them calls it first).
    """
    if fileno_of(sys.__stderr__) != 2:  # started without stderr (2>&-): fd 2 may be any file opened since
        yield lambda: None
        return
    with contextlib.suppress(Exception):
        sys.stderr.flush()
    terminal_fd = os.dup(2)
    terminal = open(terminal_fd, "w", buffering=1, encoding=_encoding(), errors="backslashreplace")  # noqa: SIM115
    read_fd, write_fd = os.pipe()
    os.set_blocking(read_fd, False)
    os.set_blocking(write_fd, False)
    os.dup2(write_fd, 2)
    os.close(write_fd)
    moved = _point_at(terminal, _on_fd_2())
    lines = NativeLines(read_fd, events, asyncio.get_running_loop())
    events.add_holder(lines.emit_held)  # the run's record closes with every line and count written so far
    try:
        yield lines.flush
    finally:
        events.remove_holder(lines.emit_held)
        os.dup2(terminal_fd, 2)
        for restore in moved:
            restore()
        lines.close()
        terminal.close()


class NativeLines:
    """The pipe's reading end, read on the loop whenever it has data; its lines become events within a budget."""

    def __init__(self, fd: int, events: EventLog, loop: asyncio.AbstractEventLoop) -> None:
        self._fd = fd
        self._events = events
        self._loop = loop
        self._lines = LineSplitter(b"\n", LINE_CHARS)
        self._budget = LineBudget(self._emit, self._emit_left_out)
        loop.add_reader(fd, self.flush)

    def flush(self) -> None:
        """Emit what the pipe holds now."""
        while True:
            try:
                chunk = os.read(self._fd, 65536)
            except BlockingIOError:
                return
            if not chunk:  # every writing end is closed
                self._loop.remove_reader(self._fd)
                return
            for line in self._lines.feed(chunk):
                self._line(line)

    def emit_held(self) -> None:
        """Emit what the pipe holds and the count of the lines left out so far, now."""
        self.flush()
        self._budget.say_count()

    def close(self) -> None:
        """Emit what is left (a child process may still hold the pipe's other end) and stop reading."""
        self.flush()
        self._line(self._lines.rest())
        self._budget.close()
        self._loop.remove_reader(self._fd)
        os.close(self._fd)

    def _line(self, raw: bytes) -> None:
        if text := raw.decode("utf-8", "replace").rstrip():
            self._budget.line(text)

    def _emit(self, text: str) -> None:
        level: Level = "info" if _INFO.search(text) else "warning"
        self._events.emit(level, "platform", f"native library: {shorten(text, LINE_CHARS)}", ORIGIN)

    def _emit_left_out(self, count: int) -> None:
        self._events.emit("warning", "platform", f"native library: {count} more lines left out (too many at once)",
                          ORIGIN)


def _encoding() -> str:
    return getattr(sys.__stderr__, "encoding", None) or "utf-8"


def _on_fd_2() -> list[tuple[Any, str]]:
    """Where Python holds a file on fd 2: ``(owner, attribute)`` pairs (sys and logging's stream handlers)."""
    places: list[tuple[Any, str]] = [(sys, "stderr"), (sys, "__stderr__")]
    places += [(handler, "stream") for handler in logging.getLogger().handlers
               if isinstance(handler, logging.StreamHandler)]
    return [(owner, name) for owner, name in places if fileno_of(getattr(owner, name, None)) == 2]


def _point_at(terminal: Any, places: list[tuple[Any, str]]) -> list[Any]:
    """Point every place at ``terminal``; returns what puts each back (unless it was changed meanwhile)."""
    restores = []
    for owner, name in places:
        old = getattr(owner, name)
        setattr(owner, name, terminal)

        def restore(owner: Any = owner, name: str = name, old: Any = old) -> None:
            if getattr(owner, name) is terminal:
                setattr(owner, name, old)

        restores.append(restore)
    return restores


def fileno_of(file: Any) -> int | None:
    """The file descriptor a Python file writes on, None for one without."""
    try:
        return file.fileno()
    except (AttributeError, OSError, ValueError):
        return None
