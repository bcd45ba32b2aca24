"""Losing the terminal (the SSH session dropped) must never block or kill the run.

A hang-up does not always arrive as SIGHUP: when the shell in between ignores or swallows it, the
process only notices that the terminal answers every call with EIO. Textual writes the screen from a
writer thread through a bounded queue; if that thread dies on EIO, or waits on a terminal that stopped
taking output (an SSH connection stalled on bad Wi-Fi), the queue fills and the event loop blocks (and
with it the vehicle's hold). So:

- :class:`TerminalWatch` notices the loss three ways (SIGHUP, a failed write, EIO on a periodic
  ``tcgetattr``), points fds 0, 1, 2 at /dev/null at once, and reports it on the loop, once;
- :func:`driver_for` gives Textual a driver whose writes never raise and never wait
  (:class:`~uav_tui.output.terminal_output.TerminalOutput`: Textual's own writer waits in ``write`` once 30
  writes are queued, so a stalled terminal blocked the loop within seconds).
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
from typing import Any

from textual.drivers.linux_driver import LinuxDriver

from uav_tui.output.native_stderr import fileno_of
from uav_tui.output.terminal_output import TerminalOutput

logger = logging.getLogger(__name__)

CHECK_PERIOD_S = 0.5
"""How often the watch thread asks the terminal whether it is still there."""
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
    """A LinuxDriver whose screen writes never wait (:class:`~uav_tui.output.terminal_output.TerminalOutput`) and
    report a lost terminal to ``watch`` instead of raising."""

    class HangupSafeDriver(LinuxDriver):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            if self._file is None:
                raise RuntimeError("no terminal to draw on: stderr is closed (run uav-tui in a terminal)")
            self._output = TerminalOutput(self._file, self._repaint, self._lost, kept_write_chars=KEPT_WRITE_CHARS,
                                          name="screen-output")

        def write(self, data: str) -> None:
            self._output.write(data)

        def close(self) -> None:
            self._output.close(CLOSE_TIMEOUT_S)
            super().close()

        def _repaint(self, dropped: int) -> None:
            """Updates were dropped while the terminal was stalled: draw the whole screen again (on the loop)."""
            if not self._loop.is_closed():  # Textual's driver keeps the app's loop
                self._loop.call_soon_threadsafe(functools.partial(self._app.refresh, layout=True))

        def _lost(self, error: OSError) -> None:
            watch.lost(f"writing to the terminal failed: {error.strerror}")

    return HangupSafeDriver


def _detach_from_terminal() -> None:
    """Point stdin, stdout and stderr at /dev/null: reads and writes on the dead terminal would fail.

    Stderr is whichever fd ``sys.__stderr__`` writes on: while native output is captured
    (:mod:`uav_tui.output.native_stderr`), fd 2 is its pipe and stays so.
    """
    try:
        null = os.open(os.devnull, os.O_RDWR)
        stderr = fileno_of(sys.__stderr__)  # None: started without one, fd 2 may be any file
        for fd in (0, 1) if stderr is None else {0, 1, stderr}:
            os.dup2(null, fd)
        os.close(null)
    except OSError:
        logger.exception("could not detach from the lost terminal")
