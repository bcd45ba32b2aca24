"""One run with the dashboard: the loop, signals, ``--script``, ``--duration`` and ``--on-hangup``.

The session owns the core; the app shows it. When the terminal is lost (the SSH session dropped:
SIGHUP, or the terminal answering EIO, see :mod:`uav_tui.tui._terminal`), standard input and output
are pointed at ``/dev/null`` first. Then either the vehicle is put in hold and everything exits
(``--on-hangup stop``, the safety rule), or the screen closes and the same core keeps running
headless (``--on-hangup continue``) until ``quit`` (script, web page), SIGTERM, the end of the
script or ``--duration``; the run keeps being recorded.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import signal
import sys
import threading
from collections.abc import Iterator
from typing import Any

from uav_tui.config import Config
from uav_tui.core import CoreState, UavCore
from uav_tui.events import EventLog, Level
from uav_tui.flight.commands import Command
from uav_tui.headless import (
    EXIT_ABANDONED,
    EXIT_RECORDING_INCOMPLETE,
    EXIT_SCRIPT_FAILED,
    EXIT_UNHANDLED_ERROR,
    run_script,
    saved_run_note,
)
from uav_tui.output.native_stderr import native_stderr_as_events
from uav_tui.output.text import safe
from uav_tui.tui._terminal import CHECK_PERIOD_S, TerminalWatch, driver_for
from uav_tui.tui.app import LOG_ORIGIN, UavApp

logger = logging.getLogger(__name__)


def run_tui(config: Config, *, duration: float | None = None, script: list[tuple[int, Command]] | None = None,
            on_hangup: str = "stop") -> int:
    """Run the platform with the dashboard until the operator quits; returns the exit code.

    Args:
        config: the run's configuration.
        duration: stop by itself after this many seconds (counted from a successful start).
        script: parsed ``--script`` lines, run in the background through the same command path.
        on_hangup: ``stop`` (hold, then exit) or ``continue`` (keep running headless) on SIGHUP.
    """
    session = TuiSession(config, duration=duration, script=script, on_hangup=on_hangup)
    try:
        return asyncio.run(session.run())
    except KeyboardInterrupt:
        return 130
    finally:
        if note := saved_run_note(session.core):
            with contextlib.suppress(OSError):  # the terminal may be gone (SIGHUP)
                print(safe(note), flush=True)


class TuiSession:
    """Runs :class:`UavApp` around a :class:`UavCore`, and the core alone after a hang-up if asked."""

    def __init__(self, config: Config, *, duration: float | None = None,
                 script: list[tuple[int, Command]] | None = None, on_hangup: str = "stop") -> None:
        self.core = UavCore(config)
        self.watch = TerminalWatch(self._hangup)
        self.app = UavApp(self.core, on_started=self._started, owns_core=False, driver_class=driver_for(self.watch))
        self.duration = duration
        self.script = script
        self.on_hangup = on_hangup
        self.exit_code = 0
        self.reason = "quit"
        self.headless = False
        """True once the screen is gone and the core carries on (``--on-hangup continue``)."""
        self._stop = asyncio.Event()
        self._tasks: set[asyncio.Task[Any]] = set()

    async def run(self) -> int:
        """Run until the end; native libraries' lines on stderr are events meanwhile (they would tear the screen)."""
        with native_stderr_as_events(self.core.events):
            return await self._run()

    async def _run(self) -> int:
        loop = asyncio.get_running_loop()
        handled = {signal.SIGTERM: "SIGTERM", signal.SIGINT: "SIGINT"}
        for signum, name in handled.items():
            loop.add_signal_handler(signum, self.request_stop, name)
        loop.add_signal_handler(signal.SIGHUP, self.watch.lost, "SIGHUP")
        self.watch.start()
        try:
            with _logging_into(self.core.events):
                await self.app.run_async()
            if not self.headless and self.app.return_code not in (0, None):
                # The app may have died of the lost terminal before the watch reported it: give it a period.
                await asyncio.sleep(CHECK_PERIOD_S + 0.1)
            if self.headless and self.core.state is CoreState.RUNNING:
                await self._run_headless()
        finally:
            for task in self._tasks:
                task.cancel()
            await asyncio.gather(*self._tasks, return_exceptions=True)
            await self.core.stop(self.reason)
            self.watch.close()
            for signum in (*handled, signal.SIGHUP):
                loop.remove_signal_handler(signum)
        if self.core.failure is not None:  # also a bug met while stopping
            self.exit_code = self.exit_code or EXIT_UNHANDLED_ERROR
        if self.core.recorder is not None and self.core.recorder.incomplete:
            self.exit_code = self.exit_code or EXIT_RECORDING_INCOMPLETE
        return self.app.return_code or self.exit_code or (EXIT_ABANDONED if self.core.abandoned_calls else 0)

    def request_stop(self, reason: str, exit_code: int = 0) -> None:
        """Hold if needed and end the run (dashboard or headless)."""
        self.exit_code = self.exit_code or exit_code
        self.reason = reason
        if self.headless:
            self._stop.set()
        else:
            self._spawn(self.app.shutdown(reason, self.exit_code))

    def _hangup(self, reason: str) -> None:
        self.core.events.emit("warning", "platform", f"terminal lost ({reason}), --on-hangup {self.on_hangup}")
        if self.on_hangup == "continue" and self.core.state is CoreState.RUNNING:
            self.headless = True
            self.app.exit()
        else:
            self.request_stop(f"terminal lost ({reason})")

    def _started(self) -> None:
        if self.script is not None:
            self._spawn(self._run_script())
        if self.duration is not None:
            asyncio.get_running_loop().call_later(self.duration, self.request_stop,
                                                  f"--duration {self.duration:g} s reached")

    async def _run_script(self) -> None:
        assert self.script is not None
        failure = await run_script(self.core, self.script, self._say)
        if failure:
            self.request_stop(failure, EXIT_SCRIPT_FAILED)
        elif self.headless and self.duration is None:
            self.request_stop("script finished")
        else:  # the operator is watching: the dashboard stays theirs until they quit
            self.core.events.emit("info", "platform", "script finished; press q to quit", "script")

    def _say(self, text: str) -> None:
        self.core.events.emit("error", "platform", text, "script")

    async def _run_headless(self) -> None:
        logger.warning("terminal lost: the core keeps running headless (--on-hangup continue)")
        quit_watch = asyncio.ensure_future(self.core.quit_requested.wait())
        stop_watch = asyncio.ensure_future(self._stop.wait())
        await asyncio.wait([quit_watch, stop_watch], return_when=asyncio.FIRST_COMPLETED)
        if not self._stop.is_set():
            self.reason = "quit"
        for task in (quit_watch, stop_watch):
            task.cancel()

    def _spawn(self, coro: Any) -> None:
        task = asyncio.ensure_future(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)



class _EventLogHandler(logging.Handler):
    """Log records as warning/error events: on the dashboard a line on stderr would tear the screen."""

    def __init__(self, events: EventLog) -> None:
        super().__init__(logging.WARNING)
        self.events = events
        self._inside = threading.local()

    def emit(self, record: logging.LogRecord) -> None:
        if getattr(self._inside, "active", False) or record.name == "uav_tui.events":
            return  # EventLog logs what it emits: never loop
        self._inside.active = True
        try:
            level: Level = "error" if record.levelno >= logging.ERROR else "warning"
            self.events.emit(level, "platform", f"{record.name}: {record.getMessage()}", origin=LOG_ORIGIN)
        finally:
            self._inside.active = False


@contextlib.contextmanager
def _logging_into(events: EventLog) -> Iterator[None]:
    """While the dashboard is up, log records that would go to the terminal go to the event log."""
    root = logging.getLogger()
    to_terminal = [h for h in root.handlers if isinstance(h, logging.StreamHandler)
                   and getattr(h, "stream", None) in (sys.stderr, sys.stdout)]
    handler = _EventLogHandler(events)
    for old in to_terminal:
        root.removeHandler(old)
    root.addHandler(handler)
    try:
        yield
    finally:
        root.removeHandler(handler)
        for old in to_terminal:
            root.addHandler(old)
