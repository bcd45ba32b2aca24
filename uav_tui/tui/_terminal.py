"""Losing the terminal (the SSH session dropped) must never block or kill the run.

A hang-up does not always arrive as SIGHUP: when the shell in between ignores or swallows it, the
process only notices that the terminal answers every call with EIO. Textual writes the screen from a
writer thread through a bounded queue; if that thread dies on EIO, or waits on a terminal that stopped
taking output (an SSH connection stalled on bad Wi-Fi), the queue fills and the event loop blocks (and
with it the vehicle's hold). So:

- :class:`TerminalWatch` notices the loss three ways (SIGHUP, a failed write, EIO on a periodic
  ``tcgetattr``), points fds 0, 1, 2 at /dev/null at once, and reports it on the loop, once;
- :func:`driver_for` gives Textual a driver whose writes never raise and never wait
  (:class:`ScreenOutput`).
"""

from __future__ import annotations

import asyncio
import errno
import functools
import logging
import os
import sys
import termios
import threading
from collections.abc import Callable
from typing import Any, TextIO

from textual.drivers.linux_driver import LinuxDriver

logger = logging.getLogger(__name__)

CHECK_PERIOD_S = 0.5
"""How often the watch thread asks the terminal whether it is still there."""
MAX_BACKLOG_CHARS = 512 * 1024
"""Screen output not yet taken by the terminal beyond which updates are dropped (a few full screens)."""
KEPT_WRITE_CHARS = 64
"""Writes this short (terminal modes: alternate screen, mouse, cursor) are never dropped."""
CLOSE_TIMEOUT_S = 1.0
"""How long closing the dashboard waits for a stalled terminal to take the last of its output."""


class TerminalWatch:
    """Calls ``on_lost(reason)`` on the loop, once, when the controlling terminal goes away.

    Args:
        on_lost: what the session does (hold and exit, or carry on headless).
    """

    def __init__(self, on_lost: Callable[[str], None]) -> None:
        self.on_lost = on_lost
        self.lost_reason = ""
        """Why the terminal counts as lost ("" while it is there)."""
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        """Start watching (from the loop that ``on_lost`` must run on)."""
        self._loop = asyncio.get_running_loop()
        self._thread = threading.Thread(target=self._poll, name="terminal-watch", daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2 * CHECK_PERIOD_S)

    def lost(self, reason: str) -> None:
        """The terminal is gone (any thread): detach from it now, report on the loop once."""
        with self._lock:
            if self.lost_reason:
                return
            self.lost_reason = reason
        _detach_from_terminal()
        loop = self._loop
        if loop is not None and not loop.is_closed():
            loop.call_soon_threadsafe(self.on_lost, reason)

    def _poll(self) -> None:
        fd = sys.__stdin__.fileno() if sys.__stdin__ is not None else 0
        while not self._stop.wait(CHECK_PERIOD_S) and not self.lost_reason:
            try:
                termios.tcgetattr(fd)
            except termios.error as exc:
                if exc.args and exc.args[0] == errno.EIO:
                    self.lost("the terminal stopped answering (EIO)")
                    return


def driver_for(watch: TerminalWatch) -> type[LinuxDriver]:
    """A LinuxDriver whose screen writes never wait (:class:`ScreenOutput`) and report a lost terminal to
    ``watch`` instead of raising."""

    class HangupSafeDriver(LinuxDriver):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            self._output = ScreenOutput(_QuietFile(self._file, watch), self._repaint)

        def write(self, data: str) -> None:
            self._output.write(data)

        def close(self) -> None:
            self._output.close(CLOSE_TIMEOUT_S)
            super().close()

        def _repaint(self) -> None:
            """Updates were dropped while the terminal was stalled: draw the whole screen again (on the loop)."""
            if not self._loop.is_closed():  # Textual's driver keeps the app's loop
                self._loop.call_soon_threadsafe(functools.partial(self._app.refresh, layout=True))

    return HangupSafeDriver


class ScreenOutput:
    """The screen's output, written to the terminal by a thread of its own: ``write`` never waits.

    Textual's own writer waits in ``write`` once 30 writes are queued, so a terminal that stops taking output
    (an SSH connection stalled on bad Wi-Fi) blocked the event loop, and the flight link with it, within
    seconds. Here screen updates that would take the backlog past ``max_backlog`` characters are dropped,
    whole (never a piece of an escape sequence); short writes (terminal modes) are always kept. Once the
    terminal has taken everything, ``on_drained`` is called if anything was dropped, to repaint the screen.
    """

    def __init__(self, file: TextIO | _QuietFile, on_drained: Callable[[], None],
                 max_backlog: int = MAX_BACKLOG_CHARS) -> None:
        self._file = file
        self._on_drained = on_drained
        self._max_backlog = max_backlog
        self._pending: list[str] = []
        self._backlog = 0
        self._dropped = False
        self._closing = False
        self._ready = threading.Condition()
        self._thread = threading.Thread(target=self._run, name="terminal-output", daemon=True)
        self._thread.start()

    def write(self, text: str) -> None:
        with self._ready:
            if len(text) > KEPT_WRITE_CHARS and self._backlog and self._backlog + len(text) > self._max_backlog:
                self._dropped = True
                return
            self._pending.append(text)
            self._backlog += len(text)
            self._ready.notify()

    def close(self, timeout: float) -> None:
        """Write what is pending, waiting at most ``timeout`` s (the terminal may be stalled), then stop."""
        with self._ready:
            self._closing = True
            self._ready.notify()
        self._thread.join(timeout)

    def _run(self) -> None:
        while True:
            with self._ready:
                self._ready.wait_for(lambda: self._pending or self._closing)
                if not self._pending:
                    return
                text, self._pending = "".join(self._pending), []
            self._file.write(text)  # may wait for the terminal: only this thread waits
            self._file.flush()
            with self._ready:
                self._backlog -= len(text)
                drained = self._dropped and not self._pending
                if drained:
                    self._dropped = False
            if drained:
                self._on_drained()


class _QuietFile:
    """Forwards writes to the terminal; an OSError means it is gone: reported, then writes are dropped."""

    def __init__(self, file: TextIO, watch: TerminalWatch) -> None:
        self._file = file
        self._watch = watch

    def write(self, text: str) -> None:
        try:
            self._file.write(text)
        except OSError as exc:
            self._watch.lost(f"writing to the terminal failed: {exc.strerror}")

    def flush(self) -> None:
        try:
            self._file.flush()
        except OSError as exc:
            self._watch.lost(f"writing to the terminal failed: {exc.strerror}")

    def fileno(self) -> int:
        return self._file.fileno()


def _detach_from_terminal() -> None:
    """Point stdin, stdout and stderr at /dev/null: reads and writes on the dead terminal would fail."""
    try:
        null = os.open(os.devnull, os.O_RDWR)
        for fd in (0, 1, 2):
            os.dup2(null, fd)
        os.close(null)
    except OSError:
        logger.exception("could not detach from the lost terminal")
