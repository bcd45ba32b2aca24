"""The platform core: source, processor worker, flight controller, telemetry and autonomy on one loop.

Interfaces (TUI, headless runner, web page) start a :class:`UavCore`, read :meth:`UavCore.status`,
listen to processed frames and events, and send operator commands through :meth:`UavCore.execute`.
"""

from __future__ import annotations

import asyncio
import functools
import logging
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import psutil

from controllers.base import BlockingCalls, FlightController, RecordedVehicle
from controllers.replay_timeline import ReplayTimeline
from sources import CameraSource
from uav_tui.camera.active import ActiveCamera
from uav_tui.config import Config
from uav_tui.errors import UavError
from uav_tui.events import EventLog
from uav_tui.flight.autonomy import AutonomyGate
from uav_tui.flight.commands import Command, parse
from uav_tui.flight.exit_hold import hold_before_exit, mode_left_at_exit
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.flight.track_lock import TrackLock
from uav_tui.flight.track_overlay import draw_tracks
from uav_tui.hosting.exception_reports import ProcessorErrors
from uav_tui.hosting.host import ProcessedFrame, ProcessorHost
from uav_tui.hosting.malloc_tuning import tune_this_process
from uav_tui.operations import Operations, build_operations
from uav_tui.output.text import last_line, shorten
from uav_tui.recording import NotRecording, Recorder, describe
from uav_tui.relays.contract import HandledFrame, OutputRelay
from uav_tui.relays.precland import LandingTargetFeed
from uav_tui.relays.registry import consider_all, landing_target_relay
from uav_tui.replay.operator import CommandReplay, recorded_commands
from uav_tui.start_parts import Parts, build_parts
from uav_tui.status import CoreState, CoreStatus, core_status
from uav_tui.web.side_channels import SideChannels
from uav_values.camera import CameraModel

if TYPE_CHECKING:  # aiortc and pymavlink are imported only when the side channels are switched on
    from uav_tui.web import WebServer
    from uav_tui.web.mavlink_tracking import CameraTracking

logger = logging.getLogger(__name__)


class UavCore:
    """Owns every long-lived part of a run and the tasks that drive them.

    Args:
        config: the run's configuration.
    """

    def __init__(self, config: Config) -> None:
        self.config = config
        self.state = CoreState.NEW
        self.events = EventLog()
        self.lock = TrackLock(self.events, lambda: self.gate.envelope.config.lost_after_s,
                              lambda t_ns: self.telemetry.at(t_ns)[0].gimbal_pitch_deg)
        """The operator's lock on a track: while on, its vector (or gimbal pointing) is the frame's (``lock ID``,
        ``unlock``)."""
        self.landing = LandingTargetFeed(self.events)
        """The processor's landing targets and the operator's ``precland`` switch."""
        self.active_camera = ActiveCamera(config.camera, self.events, self._spawn)
        """The source frames come from and its camera model (``source`` and ``camera`` read it)."""
        self.parts: Parts | None = None
        """The run's parts, once :meth:`start` built them (:func:`~uav_tui.start_parts.build_parts`)."""
        self.recorder: Recorder | None = None
        """Writes the run's dataset (None with ``--no-record``)."""
        self.quit_requested = asyncio.Event()
        """Set by the ``quit`` command; the interface that runs the core then stops it."""
        self.failure: str | None = None
        """Set by :meth:`fail`: an unhandled error ended the run (the interface exits non-zero, after the hold)."""
        self.started_wall_ns = 0
        self.startup_s: float | None = None
        """Seconds from the process start to the first processed frame (None until it is processed)."""
        self.last: HandledFrame | None = None
        """The newest processed frame and what the platform did with it (None before the first)."""
        self._frame_listeners: list[Callable[[HandledFrame], None]] = []
        self._tasks: list[asyncio.Task[Any]] = []
        self._processor_errors = ProcessorErrors(self.events)
        self._operations: Operations | None = None
        self.side_channels = SideChannels(config.web, self.events)
        """The web page and MAVLink click-to-track, when configured (``web`` and ``camera_tracking`` read it)."""
        self.abandoned_calls: list[str] = []
        """Flight-controller calls still blocked when the core stopped (the process should exit non-zero)."""

    # -- lifecycle -------------------------------------------------------------------------------

    async def start(self) -> None:
        """Build the parts (load the processor, connect the vehicle), open the camera, start the loop's tasks.

        Raises a UavError subclass that says what to fix; nothing stays open when it does.
        """
        if self.state is not CoreState.NEW:
            raise RuntimeError(f"UavCore.start() called in state {self.state.value}; a core starts once")
        loop = asyncio.get_running_loop()
        self.events.bind(loop)
        self.started_wall_ns = time.time_ns()
        tune_this_process()  # the processor's own process gets the same at its start
        # The camera's one-off preparation (the sim: camera's ground) overlaps loading and connecting.
        camera_ready = self.active_camera.warm_up(self.config.source)
        try:
            self.parts = parts = await build_parts(self.config, self.events, self.active_camera, self.lock,
                                                   self.landing, self._on_result, self._on_processor_fault)
            worker, controller, telemetry, gate = parts.worker, parts.controller, parts.telemetry, parts.gate
            if isinstance(controller, RecordedVehicle):  # a replay: it waits for each frame; the operator's again
                self.add_frame_listener(lambda result: controller.timeline.frame_done())
                controller.timeline.before_show = CommandReplay(
                    functools.partial(self.execute, origin="replay"), lambda: self.state, loop,
                    recorded_commands(controller.run_dir)).before_show
            await gate.check_autopilot_failsafe()
            worker.bind_telemetry(telemetry)
            await camera_ready
            source = await self.active_camera.start(self.config.source)
            if self.config.recording.record:
                self.recorder = await loop.run_in_executor(None, functools.partial(
                    Recorder.open, self.config.recording,
                    describe(self.config, self.started_wall_ns, self.active_camera, worker.processor, controller),
                    telemetry_expected=controller is not None, started_wall_ns=self.started_wall_ns,
                    replayed=parts.replay is not None))
                self.recorder.attach(self.events, telemetry, worker, self.active_camera)
                self.add_frame_listener(self.recorder.on_frame)
            else:
                telemetry.saver = NotRecording(self.events)
        except BaseException:
            await self._release()
            raise
        worker.attach(source.buffer, self.camera)
        self._spawn(worker.run(), "processor")
        self._spawn(telemetry.run(), "telemetry")
        if parts.link is not None:
            self._spawn(parts.link.run(), "link")
        self._spawn(gate.run(), "autonomy")
        self._spawn(gate.watch(self.newest_frame_age, lambda: worker.busy_s, lambda: worker.consecutive_errors),
                    "watchdog")
        if (landing := landing_target_relay(parts.relays)) is not None:
            self._spawn(landing.watch(controller, self.newest_frame_age, worker), "precland watchdog")
        self._operations = build_operations(parts, self.recorder, self._processor_errors, self.quit_requested)
        self.state = CoreState.RUNNING
        self.events.emit("info", "platform", f"started: source {self.config.source}, processor "
                         f"{worker.processor.info.name} ({self.config.isolation}), fc {self.config.fc}")
        try:
            await self.side_channels.start(self)
        except BaseException:
            await self._release()
            raise

    def _on_processor_fault(self, reason: str) -> None:
        """The processor's process died or was killed: autonomy off, and hold if a vector flies."""
        self._processor_errors.last = reason
        self.landing.end(f"processor fault: {reason}")
        if self.parts is not None and self.parts.gate.enabled:
            self._spawn(self.parts.gate.disable("watchdog", reason), "processor fault")

    async def stop(self, reason: str = "quit") -> None:
        """Hold the vehicle if something uav-tui started could be flying it, then release everything. Idempotent.

        A vehicle that lands, returns, flies a mission or is flown by hand is left to it
        (:data:`~uav_tui.flight.exit_hold.LEFT_ALONE_AT_EXIT`).
        """
        if self.state is CoreState.STOPPED:
            return
        self._processor_errors.flush()
        self.events.emit("info", "platform", f"stopping: {reason}")
        if (parts := self.parts) is not None:  # built: the gate is told, the vehicle held if needed
            await parts.gate.disable("platform", reason if parts.gate.enabled else None, hold=False)
            vehicle = parts.telemetry.snapshot()
            if parts.controller is not None and (parts.controller.vector_active or vehicle.in_air):
                await hold_before_exit(parts.controller, self.mode_left_at_exit(), self.events)
        await self._release()

    def mode_left_at_exit(self) -> str | None:
        """The mode the vehicle is left in at exit, or None: it is held first (:func:`.mode_left_at_exit`)."""
        handed_over = self._operations.handed_over if self._operations is not None else None
        return mode_left_at_exit(self.telemetry.snapshot().flight_mode, self.controller, handed_over)

    async def _release(self) -> None:
        """Release every part, each one even if another failed (a bug, reported): the dataset is always closed."""
        for part, release in (("side channels", self.side_channels.stop), ("tasks", self._cancel_tasks),
                              ("processor", self._close_worker), ("camera", self.active_camera.close),
                              ("flight controller", self._close_controller), ("recorder", self._close_recorder)):
            try:
                await release()
            except Exception as exc:  # noqa: BLE001 - reported; the parts after it must still be released
                self.fail(f"releasing the {part}", exc)
        self.state = CoreState.STOPPED

    async def _cancel_tasks(self) -> None:
        for relay in self.relays.values():
            await relay.close()
        for task in self._tasks:
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        self._tasks.clear()

    async def _close_worker(self) -> None:
        if self.parts is not None:
            self.parts.worker.close()

    async def _close_controller(self) -> None:
        if (controller := self.controller) is not None:
            await controller.close()
            if isinstance(controller, BlockingCalls):
                self.abandoned_calls = list(controller.unfinished_calls)
            if self.abandoned_calls:
                self.events.emit("error", "link", "flight controller calls still blocked, abandoned: "
                                 + ", ".join(self.abandoned_calls))

    async def _close_recorder(self) -> None:
        if self.recorder is not None:
            self.telemetry.saver = None
            self.events.emit_held()  # FFmpeg's last lines, at the camera's close, and a flood's count: recorded
            await asyncio.get_running_loop().run_in_executor(None, self.recorder.close)

    def _spawn(self, coro: Any, name: str) -> None:
        task = asyncio.create_task(coro, name=name)
        task.add_done_callback(self._task_done)
        self._tasks.append(task)

    def _task_done(self, task: asyncio.Task[Any]) -> None:
        if not task.cancelled() and (exc := task.exception()) is not None:
            self.fail(f"the {task.get_name()} task", exc)

    def fail(self, where: str, exc: BaseException) -> None:
        """An unhandled error (a bug): log it and end the run; the interface holds the vehicle (safety rule 6)."""
        logger.error("unhandled error in %s", where, exc_info=exc)
        if self.failure is None:
            self.failure = f"unhandled error in {where}: {exc!r}"
            self.events.emit("error", "platform", f"{self.failure}; stopping")
        self.quit_requested.set()

    # -- what the interfaces read ----------------------------------------------------------------

    @property
    def worker(self) -> ProcessorHost | None:
        """The processor's host (None before the start)."""
        return self.parts.worker if self.parts is not None else None

    @property
    def controller(self) -> FlightController | None:
        """The vehicle (None before the start, and with ``--fc none``)."""
        return self.parts.controller if self.parts is not None else None

    @property
    def replay(self) -> ReplayTimeline | None:
        """Where a replay is on the recorded clock (``--fc replay:RUN``), else None."""
        return self.parts.replay if self.parts is not None else None

    @property
    def relays(self) -> dict[str, OutputRelay]:
        """The output relays by field ({} before the start)."""
        return self.parts.relays if self.parts is not None else {}

    @property
    def telemetry(self) -> TelemetryManager:
        """The vehicle's telemetry (once started)."""
        assert self.parts is not None, "the telemetry comes with start()"
        return self.parts.telemetry

    @property
    def gate(self) -> AutonomyGate:
        """The autonomy gate (once started)."""
        assert self.parts is not None, "the autonomy gate comes with start()"
        return self.parts.gate

    @property
    def source(self) -> CameraSource | None:
        """The camera frames come from now (None before it is open)."""
        return self.active_camera.source

    @property
    def camera(self) -> CameraModel | None:
        """The source's camera model (its own, or the configured one; None: none known); ``tmMgr.camera()``."""
        return self.active_camera.model

    @property
    def web(self) -> WebServer | None:
        """The web page's WebServer (``web.url`` has the token) when ``web`` is on, else None."""
        return self.side_channels.web

    @property
    def camera_tracking(self) -> CameraTracking | None:
        """The MAVLink camera component when ``camera_mavlink`` is set, else None."""
        return self.side_channels.camera_tracking

    @property
    def processor_error(self) -> str | None:
        """Last line of the newest processor traceback (or why its process died); None since a reload."""
        return self._processor_errors.last

    # -- frames ----------------------------------------------------------------------------------

    def add_frame_listener(self, listener: Callable[[HandledFrame], None]) -> None:
        """Call ``listener(handled)`` on the loop for every processed frame, once the gate and the relays acted."""
        self._frame_listeners.append(listener)

    def remove_frame_listener(self, listener: Callable[[HandledFrame], None]) -> None:
        if listener in self._frame_listeners:
            self._frame_listeners.remove(listener)

    def _on_result(self, result: ProcessedFrame) -> None:
        try:
            self._handle_result(result)
        except Exception as exc:  # noqa: BLE001 - a bug on the loop: stop the run, never keep flying
            self.fail(f"frame {result.frame.seq}", exc)

    def _handle_result(self, result: ProcessedFrame) -> None:
        if self.startup_s is None:
            self.startup_s = time.time() - psutil.Process().create_time()
            self.events.emit("info", "platform", f"first frame processed {self.startup_s:.1f} s after the "
                             "process started")
        if result.outcome.error:
            exception = shorten(last_line(result.outcome.error), 500)
            self._processor_errors.report(result.outcome.error, exception, result.frame.seq)
        result, lock = self.lock.steer(result), self.lock.held
        if result.frame.image.flags.writeable:
            draw_tracks(result.frame.image, result.outcome.detections, self.lock.status(), self.lock.vector)
        decision = self.gate.consider(result)
        self.last = handled = HandledFrame(result, decision, consider_all(self.relays, result), lock)
        for listener in tuple(self._frame_listeners):
            listener(handled)

    def newest_frame_age(self) -> float | None:
        """Seconds since the newest frame's capture (on the gate's clock), None before the first."""
        return self.active_camera.newest_frame_age(self.gate.clock)

    # -- commands --------------------------------------------------------------------------------

    async def execute(self, command: Command | str, origin: str = "script") -> str:
        """Run one operator command; returns what happened, raises UavError saying why it could not."""
        parsed = parse(command) if isinstance(command, str) else command
        if parsed is None:
            return ""
        if self._operations is None or self.state is not CoreState.RUNNING:
            raise UavError(f"{parsed}: the platform is not running")
        return await self._operations.execute(parsed, origin)

    # -- status ----------------------------------------------------------------------------------

    def status(self) -> CoreStatus:
        """Everything an interface shows, as one immutable snapshot."""
        assert self.parts is not None, "a core has a status once started"
        return core_status(self.parts, self.last, self.recorder, self.processor_error, self.startup_s)
