"""``UavApp``: the operator dashboard. Every key sends a command of :mod:`uav_tui.flight.commands` to the core."""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np
from textual.app import App, ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.css.query import NoMatches
from textual.driver import Driver

from uav_tui.core import CoreState, UavCore
from uav_tui.errors import KNOWN_ERRORS, CommandError, error_line
from uav_tui.events import Event
from uav_tui.flight.commands import VEHICLE_COMMANDS, parse
from uav_tui.headless import EXIT_UNHANDLED_ERROR
from uav_tui.output.native_stderr import ORIGIN as NATIVE_ORIGIN
from uav_tui.output.text import safe
from uav_tui.status import CoreStatus
from uav_tui.tui._algorithm import AlgorithmPanel
from uav_tui.tui._event_log import EventLogView
from uav_tui.tui._header import StatusBar
from uav_tui.tui._keybar import KeyBar, key_name
from uav_tui.tui._panel import StatusPanel
from uav_tui.tui._pipeline import PipelinePanel
from uav_tui.tui._preview import FramePreview, FrameProvider
from uav_tui.tui._telemetry import TelemetryPanel
from uav_tui.tui.screens import CommandPrompt, ConfirmScreen

logger = logging.getLogger(__name__)

LOG_ORIGIN = "log"
"""Origin of events that are log records (shown in the log, not popped up: they are for developers)."""

STATUS_HZ = 2.0
"""How often the panels are refreshed from ``core.status()``."""


@dataclass(frozen=True)
class Key:
    """One key of the dashboard: the command text it sends and, for dangerous ones, the question."""

    key: str
    command: str
    label: str
    confirm: str = ""
    """Asked in a :class:`ConfirmScreen` before sending; empty: sent at once."""


KEYS: tuple[Key, ...] = (
    Key("h", "hold", "Hold"),
    Key("l", "land", "Land"),
    Key("p", "precland", "PrecLand"),
    Key("r", "rtl", "RTL"),
    Key("a", "arm", "Arm", "ARM the motors? Props will spin."),
    Key("t", "takeoff", "Takeoff", "TAKE OFF now?"),
    Key("d", "disarm", "Disarm", "DISARM the motors? In the air the vehicle would fall."),
    Key("o", "orbit 10 2", "Orbit"),
    Key("g", "autonomy toggle", "Auto"),
    *(Key(f"f{n}", f"f {n}", f"processor button {n}") for n in range(1, 5)),
    Key("s", "snapshot", "Snap"),
    Key("R", "reload", "Reload"),
)
"""The command keys, in footer order (hold and land first: they are what an operator looks for)."""

CONFIRM = {k.command.split()[0]: k.confirm for k in KEYS if k.confirm}
"""Command word -> the question asked before it is sent, by key or typed."""

FUNCTION_KEYS = Binding.Group("processor")
"""F1-F4 share one footer entry."""

NEEDS_VEHICLE = VEHICLE_COMMANDS | {"autonomy"}
"""Commands dimmed without a flight controller (``--fc none``)."""

CAPABILITY_OF_COMMAND = {"f": "customize_processing", "roi": "catch_cmd", "precland": "getLandingTarget"}
"""Commands that only apply when the processor has the method."""


class UavApp(App[None]):
    """The dashboard around a :class:`UavCore`, which it starts on mount and stops on exit.

    Args:
        core: the platform core (not started yet, or already running).
        status: where the panels read the status from (default: ``core.status``); tests pass a fixed one.
        frames: where the preview reads frames from (default: the worker's newest processed frame).
        on_started: called once the core runs (the session starts ``--script`` and ``--duration`` there).
        owns_core: stop the core when the app ends, however it ends (False: the caller stops it).
        driver_class: the Textual driver (the session's survives a lost terminal).
    """

    CSS_PATH = "app.tcss"
    TITLE = "uav-tui"
    ENABLE_COMMAND_PALETTE = False
    BINDINGS: ClassVar[list[BindingType]] = [
        *(Binding(k.key, f"send({k.command!r})", k.label, group=FUNCTION_KEYS if k.key.startswith("f") else None)
          for k in KEYS),
        Binding("b", "roi_box", "ROI box"),
        Binding("colon", "prompt", "Command"),
        Binding("q", "quit", "Quit"),
        Binding("question_mark", "help", "Help"),
        Binding("escape", "hide_help_panel", "Close help", show=False),
    ]

    def __init__(self, core: UavCore, *, status: Callable[[], CoreStatus] | None = None,
                 frames: FrameProvider | None = None, on_started: Callable[[], None] | None = None,
                 owns_core: bool = True, driver_class: type[Driver] | None = None) -> None:
        super().__init__(driver_class=driver_class)
        self.core = core
        self._status = status
        self._frames = frames or self._newest_frame
        self._on_started = on_started
        self.owns_core = owns_core
        self.stop_reason = "quit"
        self.start_error = ""
        """Why the core could not start ("" if it did); also printed when the app exits."""
        self._stopping = False

    def compose(self) -> ComposeResult:
        yield StatusBar(self.core.config.safety.link_timeout)
        with Horizontal(id="body"):
            with Vertical(id="left"):
                yield TelemetryPanel(id="telemetry")
                yield PipelinePanel(id="pipeline")
                yield AlgorithmPanel(id="algorithm")
            with Vertical(id="right"):
                with Vertical(id="preview-box"):
                    yield FramePreview(self._frames, id="preview")
                yield EventLogView(id="events")
        yield KeyBar()

    def on_mount(self) -> None:
        self.query_one("#preview-box").border_title = "Preview (drag or b: ROI)"
        self.core.events.add_listener(self.on_core_event)
        self.run_worker(self._start_core(), name="start core", exit_on_error=False)

    async def _start_core(self) -> None:
        if self.core.state is CoreState.NEW:
            try:
                await self.core.start()
            except KNOWN_ERRORS as exc:
                self._start_failed(str(exc))
                return
            except Exception as exc:
                logger.exception("UavCore failed to start")
                self._start_failed(f"{type(exc).__name__}: {exc}")
                return
        if self.core.web is not None:  # with its token: shown here, never recorded (events redact it)
            self.query_one(EventLogView).write(f"web page: {self.core.web.url}")
        self.set_interval(1 / STATUS_HZ, self.refresh_status)
        self.refresh_status()
        self.describe_buttons()
        self.run_worker(self._watch_quit(), name="quit watch", exit_on_error=False)
        if self._on_started is not None:
            self._on_started()

    def _start_failed(self, reason: str) -> None:
        self.start_error = reason
        self.exit(return_code=2, message=safe(error_line(f"cannot start: {reason}"), multiline=True))

    async def _watch_quit(self) -> None:
        await self.core.quit_requested.wait()
        failure = self.core.failure
        await self.shutdown(failure or "quit", EXIT_UNHANDLED_ERROR if failure else 0)

    async def shutdown(self, reason: str, return_code: int = 0) -> None:
        """Stop the core (it holds the vehicle where something uav-tui started may fly it), then exit."""
        if self._stopping:
            return
        self._stopping, self.stop_reason = True, reason
        self.notify(f"stopping ({reason}): holding the vehicle if needed", timeout=10, markup=False)
        try:
            await self.core.stop(reason)
        finally:  # a bug in stopping must not leave the dashboard up on a terminal that may be gone
            self.exit(return_code=return_code)

    async def on_unmount(self) -> None:
        self.core.events.remove_listener(self.on_core_event)
        if self.owns_core:
            await self.core.stop(self.stop_reason)

    # -- status and events -----------------------------------------------------------------------

    def refresh_status(self) -> None:
        """Read one snapshot and hand it to every panel."""
        if self._status is None and self.core.state is not CoreState.RUNNING:
            return
        status = (self._status or self.core.status)()
        try:
            self.query_one(StatusBar).show(status)
        except NoMatches:  # its children are not mounted yet (a fast start); the next tick shows it
            return
        for panel in self.query(StatusPanel):
            panel.status = status

    def on_core_event(self, event: Event) -> None:
        """Log every event; warnings and errors also pop up (except log records and native libraries' lines)."""
        if not self.is_running:
            return
        self.query_one(EventLogView).add_event(event)
        if event.level != "info" and event.origin not in (LOG_ORIGIN, NATIVE_ORIGIN):
            self.notify(event.message, title=event.kind, severity=event.level, timeout=6, markup=False)

    def _newest_frame(self) -> tuple[int, np.ndarray, tuple[int, int, int, int] | None] | None:
        last = self.core.last
        return None if last is None else (last.frame.t_mono_ns, last.frame.image, last.outcome.box)

    # -- commands --------------------------------------------------------------------------------

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """Dim the keys that cannot apply: vehicle commands without a vehicle, methods the processor lacks."""
        if action == "roi_box":
            parameters, action = ("roi",), "send"
        if action == "send" and parameters:
            word = str(parameters[0]).split()[0]
            if word in NEEDS_VEHICLE and self.core.state is CoreState.RUNNING and self.core.controller is None:
                return None
            method = CAPABILITY_OF_COMMAND.get(word)
            if method and self.core.worker is not None and method not in self.core.worker.processor.info.capabilities:
                return None
        return True

    def action_send(self, command: str) -> None:
        """Send ``command``; dangerous ones after a confirmation."""
        word = command.split()[0].lower() if command.split() else ""
        if word == "quit":
            self.run_worker(self.action_quit(), exit_on_error=False)
            return
        question = CONFIRM.get(word, "")
        if question:
            label = command.split()[0].capitalize()
            self.push_screen(ConfirmScreen(question, label), lambda yes: self.send(command) if yes else None)
        else:
            self.send(command)

    def send(self, command: str) -> None:
        """Run ``command`` through the core in the background; failures are shown, never raised."""
        self.run_worker(self._execute(command), group="commands", exit_on_error=False)

    async def _execute(self, text: str) -> None:
        try:
            command = parse(text)
        except CommandError as exc:
            self._command_failed(str(exc))
            return
        if command is None:
            return
        if self.core.state is not CoreState.RUNNING:
            self._command_failed(f"{command}: the platform is not running (yet)")
            return
        try:
            await self.core.execute(command, origin="tui")
        except KNOWN_ERRORS:
            return  # the core logged it as an error event, which on_core_event shows
        except Exception as exc:
            logger.exception("command %s failed", command)
            self._command_failed(f"{command} failed: {type(exc).__name__}: {exc}")
            return
        if command.word == "reload":
            self.describe_buttons()

    def describe_buttons(self) -> None:
        """F1-F4 in the help (``?``) say what the processor's class docstring says they do (``Operator buttons:``);
        the keys it lacks are dimmed (:meth:`check_action`)."""
        if self.core.worker is not None:
            meanings = dict(self.core.worker.processor.info.buttons)
            for key in KEYS:
                if (number := key.key.removeprefix("f")).isdigit():
                    described = meanings.get(int(number), key.label)
                    # Textual has no public way to change a binding's text; its BindingsMap is replaced in place.
                    self._bindings.key_to_bindings[key.key] = [
                        replace(binding, description=described) for binding in self._bindings.key_to_bindings[key.key]]
        self.refresh_bindings()

    def get_key_display(self, binding: Binding) -> str:
        """Keys as the key bar names them (``F1``, ``?``, ``:``), in the help too; the others as Textual does."""
        name = key_name(binding)
        return name if name != binding.key.split(",")[0] else super().get_key_display(binding)

    def _command_failed(self, message: str) -> None:
        self.core.events.emit("error", "command", message, "tui")

    def on_frame_preview_roi_selected(self, message: FramePreview.RoiSelected) -> None:
        self.send("roi {} {} {} {}".format(*message.roi))

    def on_frame_preview_point_clicked(self, message: FramePreview.PointClicked) -> None:
        """A click inside a track's box on the newest frame locks that track."""
        if (track := self.core.lock.track_at(message.x, message.y)) is not None:
            self.send(f"lock {track}")

    def action_prompt(self) -> None:
        """Type any command, as in a ``--script`` file."""
        self.push_screen(CommandPrompt(), lambda text: self.action_send(text) if text else None)

    def action_roi_box(self) -> None:
        """Keyboard ROI: a box over the preview, arrows move it, shift+arrows resize, Enter sends."""
        if not self.query_one(FramePreview).start_keyboard_box():
            self.notify("no frame to select a region in yet", severity="warning")

    async def action_quit(self) -> None:
        """Quit; while the vehicle is armed only after a confirmation that says what the exit does to it."""
        if self.core.state is not CoreState.RUNNING:
            await self.shutdown("quit")
            return
        if self.core.telemetry.snapshot().armed and self.core.replay is None:  # a replay's vehicle is a recording
            self.push_screen(ConfirmScreen(self._quit_question, "Quit"), lambda yes: self.send("quit") if yes else None)
        else:
            self.send("quit")

    def _quit_question(self) -> str:
        """What quitting does to the vehicle now (the dialog asks it again as the vehicle lands, disarms ...)."""
        if not self.core.telemetry.snapshot().armed:
            return "The vehicle is disarmed now. Quit?"
        mode = self.core.mode_left_at_exit()
        then = f"It is left in {mode} mode." if mode else "It is put in hold first."
        return f"The vehicle is ARMED. Quit? {then}"

    def action_help(self) -> None:
        if self.screen.query("HelpPanel"):
            self.action_hide_help_panel()
        else:
            self.action_show_help_panel()
