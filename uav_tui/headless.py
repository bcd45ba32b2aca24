"""``uav-tui --no-ui``: the same core without a screen, with a status line, scripts and signals."""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import signal
import sys
import time
from collections.abc import Callable, Coroutine, Iterator
from dataclasses import asdict
from pathlib import Path
from typing import Any, TextIO

from uav_tui.config import Config, Isolation, SafetyConfig
from uav_tui.core import UavCore
from uav_tui.errors import KNOWN_ERRORS, CommandError, error_line
from uav_tui.events import Event
from uav_tui.flight.commands import Command, check_limits, parse
from uav_tui.flight.geo_detections import describe_shown
from uav_tui.flight.geolocate import describe as describe_target
from uav_tui.output.line_budget import BudgetedText
from uav_tui.output.native_stderr import native_stderr_as_events
from uav_tui.output.terminal_output import TerminalOutput
from uav_tui.output.text import escape, safe, shorten
from uav_tui.status import CoreStatus, saves_dropped_text

OUTPUT_BACKLOG_CHARS = 64 * 1024
"""Lines not yet taken by a stalled terminal beyond which new ones are dropped (half a minute of ``--json``
status): once it takes output again, the operator reads the present, told how much was skipped."""
PRINTED_CHARS = 300
"""A longer line printed by a processor in this process (thread isolation) is cut."""
CLOSE_TIMEOUT_S = 1.0
"""How long the end of a run waits for a stalled terminal to take the last of its output."""

EXIT_OK, EXIT_SCRIPT_FAILED, EXIT_START_FAILED, EXIT_UNHANDLED_ERROR, EXIT_ABANDONED = 0, 1, 2, 3, 4
EXIT_RECORDING_INCOMPLETE = 5
"""The run went on, but a disk error (full, failing) kept part of its recording from the disk."""


def load_script(path: Path, safety: SafetyConfig | None = None) -> list[tuple[int, Command]]:
    """Parse a whole ``--script`` file up front, so a typo on line 9 is found before takeoff.

    With ``safety``, arguments beyond their configured limits are found then too.
    """
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise CommandError(f"cannot read script {path}: {exc.strerror}", key="script") from None
    except UnicodeDecodeError as exc:
        raise CommandError(f"script {path} is not UTF-8 text (byte {exc.start}); save it as UTF-8",
                           key="script") from None
    commands, problems = [], []
    for number, line in enumerate(lines, start=1):
        try:
            command = parse(line)
            if command is not None and safety is not None:
                check_limits(command, safety)
        except CommandError as exc:
            problems.append(f"{path}:{number}: {exc}")
            continue
        if command is not None:
            commands.append((number, command))
    if problems:
        raise CommandError("\n".join(problems), key="script")
    return commands


def format_status(status: CoreStatus, elapsed_s: float) -> str:
    """One line a status: pipeline, processor, vehicle, autonomy (wider than 80 columns with a vehicle: it wraps)."""
    p, t = status.pipeline, status.telemetry
    stalled = " STALLED" if status.source.get("stalled_since") else ""
    line = (f"{elapsed_s:6.1f}s cam {p.capture_fps:4.1f}fps{stalled} proc {p.processed_fps:4.1f}fps "
            f"age {p.frame_age_ms:3.0f}ms p50/p95 {p.processing_ms_p50:.1f}/{p.processing_ms_p95:.1f}ms "
            f"skip {p.frames_skipped} err {p.errors}")
    if status.processor_state is not None:
        line += f" | processor {status.processor_state.summary()}"
    if status.fc != "none":
        hb = "-" if status.heartbeat_age_s is None else f"{status.heartbeat_age_s:.1f}s"
        alt = "-" if t.rel_alt_m is None else f"{t.rel_alt_m:.1f}m"
        state = "armed" if t.armed else "disarmed"
        stale = "LINK LOST, stale: " if status.link_lost else ""
        line += f" | hb {hb} {stale}{t.flight_mode or '?'} {state}{' air' if t.in_air else ''} alt {alt}"
        if t.north_m is not None and t.east_m is not None:
            line += f" N {t.north_m:.1f} E {t.east_m:.1f}m"
        if status.vehicle_problem:
            line += f" ({status.vehicle_problem})"
    if status.target is not None and (where := describe_target(status.target)):
        line += f" | target {where}"
    if detected := describe_shown(status.detections, status.detections_total, status.tracks_total):
        line += f" | {detected}"
    if status.lock:
        line += f" | lock: {status.lock}"
    if status.saves_dropped:
        line += f" | {saves_dropped_text(status.saves_dropped)}"
    line += f" | auto {'ON' if status.autonomy else 'OFF'}"
    if status.last_vector is not None:
        vx, vy, vt = status.last_vector
        line += f" vec {vx:+.2f},{vy:+.2f}m/s {vt:.1f}s"
    if status.last_decision:
        line += f" ({status.last_decision})"
    if "getLandingTarget" in status.capabilities:
        line += f" | precland {'ON' if status.precland else 'OFF'} {status.landing_targets_sent} sent"
        if status.landing_targets_failed:
            line += f" {status.landing_targets_failed} failed"
        if status.landing_none_reason:
            line += f" ({status.landing_none_reason})"
    if gimbal := status.gimbal_summary():
        line += f" | {gimbal}"
    return line


def saved_run_note(core: UavCore) -> str:
    """Where the core's run was recorded and how to look at it ("" when recording was off); the runs folder is the
    operator's choice, from outside: pass the note through :func:`safe` before a terminal."""
    if core.recorder is None:
        return ""
    run_dir = core.recorder.run_dir
    return f"run saved in {run_dir}; plots and summary: uav-tui report {run_dir} (all runs: uav-tui runs)"


async def run_script(core: UavCore, script: list[tuple[int, Command]], say: Callable[[str], None]) -> str:
    """Run ``--script`` lines through ``core.execute`` (``wait`` sleeps); returns "" or why it stopped early."""
    for number, command in script:
        try:
            if command.word == "wait":
                await asyncio.sleep(command.args[0])
            else:
                await core.execute(command, origin="script")
        except KNOWN_ERRORS as exc:
            say(f"script line {number} ({command}) failed: {exc}")
            return f"script line {number} failed"
    return ""


class HeadlessRunner:
    """Runs a core until Ctrl-C, SIGTERM, SIGHUP, ``quit``, the end of the script or ``--duration``."""

    def __init__(self, config: Config, *, duration: float | None = None, script: list[tuple[int, Command]] | None
                 = None, json_lines: bool = False, on_hangup: str = "stop", out: TextIO = sys.stdout) -> None:
        self.core = UavCore(config)
        self.duration = duration
        self.script = script
        self.json_lines = json_lines
        self.on_hangup = on_hangup
        self.out = out
        self.exit_code = EXIT_OK
        self._stop = asyncio.Event()
        self._reason = "finished"

    async def run(self) -> int:
        """Run until stopped; returns the exit code. What it prints never waits for the terminal.

        Native libraries' lines on stderr (FFmpeg's, OpenCV's) are printed as events too.
        """
        with native_stderr_as_events(self.core.events) as self._flush_native_lines:
            self._stdout = TerminalOutput(self.out, self._dropped, _gone, max_backlog=OUTPUT_BACKLOG_CHARS,
                                          name="stdout")
            self._stderr = TerminalOutput(sys.stderr, self._dropped, _gone, max_backlog=OUTPUT_BACKLOG_CHARS,
                                          name="stderr")
            # print() too, the processor's for one; with --json stdout is only JSON, so prints go to stderr.
            printed = [self._printed(self._stderr if self.json_lines else self._stdout), self._printed(self._stderr)]
            try:
                with (_logging_to(self._stderr), contextlib.redirect_stdout(printed[0]),
                      contextlib.redirect_stderr(printed[1])):
                    return await self._run()
            finally:
                for stream in printed:
                    if isinstance(stream, BudgetedText):
                        stream.close()
                deadline = time.monotonic() + CLOSE_TIMEOUT_S
                for output in (self._stdout, self._stderr):
                    output.close(max(0.0, deadline - time.monotonic()))

    def _printed(self, output: TerminalOutput) -> TerminalOutput | BudgetedText:
        """Where ``print()`` goes: ``output``; with thread isolation, where the processor prints in this process,
        within a line budget (with process isolation its output has one already: ``SubprocessHost``)."""
        if self.core.config.isolation != Isolation.THREAD:
            return output
        printed = BudgetedText(output, lambda line: output.write(shorten(safe(line), PRINTED_CHARS) + "\n"),
                               self._left_out)
        self.core.events.add_holder(printed.say_count)  # its count goes into the run's record too
        return printed

    def _left_out(self, count: int) -> None:
        self.core.events.emit("warning", "processor",
                              f"{count} more lines of the processor's output left out (too many at once)")

    async def _run(self) -> int:
        loop = asyncio.get_running_loop()
        for signum, name in ((signal.SIGINT, "Ctrl-C"), (signal.SIGTERM, "SIGTERM"), (signal.SIGHUP, "SIGHUP")):
            if signum == signal.SIGHUP and self.on_hangup == "continue":
                loop.add_signal_handler(signum, self.core.events.emit, "warning", "platform",
                                        "terminal lost (SIGHUP), --on-hangup continue: the run goes on")
            else:
                loop.add_signal_handler(signum, self.request_stop, name)
        # Suspended, the platform would stop streaming to the vehicle (the autopilot's failsafe would hold it).
        loop.add_signal_handler(signal.SIGTSTP, self.core.events.emit, "warning", "platform",
                                "Ctrl-Z ignored: a suspended uav-tui would stop flying the vehicle; detach with "
                                "tmux or screen, stop with Ctrl-C")
        self.core.events.add_listener(self._print_event)  # before start: what it finds at connect is printed
        try:
            started = await self._start()
        except KNOWN_ERRORS as exc:
            self._flush_native_lines()  # what FFmpeg said of it ("Connection refused") comes first
            self._error(str(exc))
            return EXIT_START_FAILED
        if not started:
            self._say(json.dumps({"stopped": self._reason}) if self.json_lines else f"stopped: {self._reason}, "
                      "while starting")
            return self.exit_code
        try:
            await self._serve(loop)
        except BaseException as exc:  # a bug here, or the loop cancelled: the vehicle is held all the same
            self._reason = f"unhandled error: {exc!r}"
            raise
        finally:
            await self.core.stop(self._reason)
        if self.core.failure is not None and not self.exit_code:  # also a bug met while stopping
            self.exit_code = EXIT_UNHANDLED_ERROR
        if self.core.recorder is not None and self.core.recorder.incomplete and not self.exit_code:
            self.exit_code = EXIT_RECORDING_INCOMPLETE
        self._say(json.dumps({"stopped": self._reason}) if self.json_lines else f"stopped: {self._reason}")
        if (recorder := self.core.recorder) is not None:
            self._say(json.dumps({"run_dir": str(recorder.run_dir)}) if self.json_lines else saved_run_note(self.core))
        return EXIT_ABANDONED if self.core.abandoned_calls else self.exit_code

    async def _start(self) -> bool:
        """Start the core; False when a stop was asked first (Ctrl-C, SIGTERM: while a processor loads, say), which
        cancels the start and releases what it had opened."""
        start = asyncio.create_task(self.core.start(), name="start")
        stop = asyncio.create_task(self._stop.wait())
        await asyncio.wait([start, stop], return_when=asyncio.FIRST_COMPLETED)
        stop.cancel()
        if not start.done():
            start.cancel()
            await asyncio.gather(start, return_exceptions=True)
            return False
        start.result()
        return True

    async def _serve(self, loop: asyncio.AbstractEventLoop) -> None:
        """From a started core until something asks to stop; sets the reason and the exit code."""
        if self.core.web is not None:
            url = self.core.web.url
            self._say(json.dumps({"web_url": url}) if self.json_lines else f"web page: {url}", redact=False)
        started = time.monotonic()
        tasks = [self._watched(self._print_status(started), "status line")]
        if self.script is not None:
            tasks.append(self._watched(self._run_script(), "script"))
        if self.duration is not None:
            loop.call_later(self.duration, self.request_stop, f"--duration {self.duration:g} s reached")
        quit_watch = asyncio.create_task(self.core.quit_requested.wait())
        stop_watch = asyncio.create_task(self._stop.wait())
        await asyncio.wait([quit_watch, stop_watch], return_when=asyncio.FIRST_COMPLETED)
        if self.core.failure is not None:
            self._reason, self.exit_code = self.core.failure, EXIT_UNHANDLED_ERROR
        elif self.core.quit_requested.is_set() and not self._stop.is_set():
            self._reason = "quit"
        for task in (*tasks, quit_watch, stop_watch):
            task.cancel()
        await asyncio.gather(*tasks, quit_watch, stop_watch, return_exceptions=True)

    def _watched(self, coro: Coroutine[Any, Any, None], name: str) -> asyncio.Task[None]:
        """A task of this runner whose unexpected exception ends the run like any unhandled error."""
        def done(task: asyncio.Task[None]) -> None:
            if not task.cancelled() and (exc := task.exception()) is not None:
                self.core.fail(f"the {name} task", exc)

        task = asyncio.create_task(coro, name=name)
        task.add_done_callback(done)
        return task

    def request_stop(self, reason: str) -> None:
        if not self._stop.is_set():
            self._reason = reason
            self._stop.set()

    def _print_event(self, event: Event) -> None:
        if self.json_lines:
            self._say(json.dumps({"event": asdict(event)}))
        else:
            self._say(f"[{event.level}] {event.kind}: {event.message}")

    async def _run_script(self) -> None:
        assert self.script is not None
        failure = await run_script(self.core, self.script, self._error)
        if failure:
            self.exit_code = EXIT_SCRIPT_FAILED
            self.request_stop(failure)
        elif self.duration is None:
            self.request_stop("script finished")

    async def _print_status(self, started: float) -> None:
        while True:
            await asyncio.sleep(1.0)
            status = self.core.status()
            if self.json_lines:
                self._say(json.dumps({"t": round(time.monotonic() - started, 3), **status.as_dict()}, default=str))
            else:
                self._say(format_status(status, time.monotonic() - started))

    def _error(self, text: str) -> None:
        """Why the run could not start or its script failed: on stderr, as every command-line error."""
        self._stderr.write(safe(error_line(text), multiline=True) + "\n")

    def _say(self, text: str, *, redact: bool = True) -> None:
        """Print one line: escaped, and with passwords hidden unless ``redact`` is False (the page's URL)."""
        self._stdout.write((safe(text, multiline=True) if redact else escape(text)) + "\n")

    def _dropped(self, lines: int) -> None:
        """The terminal stalled and ``lines`` were not shown (writer thread): say so, in events.csv too."""
        with contextlib.suppress(RuntimeError):  # the loop closed meanwhile
            self.core.events.emit("warning", "platform", f"{lines} lines of output were dropped while the terminal "
                                  "was not taking them (events.csv has every event)")


def _gone(error: OSError) -> None:
    """A lost terminal must not stop the run: the safety rules decide that (``--on-hangup``), not a write."""


@contextlib.contextmanager
def _logging_to(stream: TerminalOutput) -> Iterator[None]:
    """While the run lasts, log records meant for the terminal go through ``stream`` (which never waits)."""
    handlers = [h for h in logging.getLogger().handlers
                if type(h) is logging.StreamHandler and h.stream in (sys.stderr, sys.stdout)]
    previous = [h.setStream(stream) for h in handlers]
    try:
        yield
    finally:
        for handler, old in zip(handlers, previous, strict=True):
            handler.setStream(old)
