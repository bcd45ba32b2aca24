"""The thread host (``isolation = "thread"``): every call into the researcher's code runs on one thread, newest
frame first."""

from __future__ import annotations

import asyncio
import contextlib
import functools
import logging
import os
import threading
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future
from typing import TYPE_CHECKING, Any

from controllers.base import TELEMETRY_FIELDS, Telemetry
from processors import LoadedProcessor, load_processor
from processors.base import ProcessorInfo
from processors.frame_telemetry import DEFAULT_SAVE_MAX_HZ, FrameTelemetry
from processors.outputs import output_methods
from sources.buffer import Frame, FrameBuffer
from uav_tui.config import Isolation
from uav_tui.events import EventLog
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.hosting.frame_call import call_frame
from uav_tui.hosting.host import (
    Answer,
    DeliversResults,
    HostPhase,
    HostState,
    ProcessedFrame,
    ProcessorState,
    StageClock,
)
from uav_tui.hosting.thread_logs import ThreadLogBudget
from uav_tui.hosting.tracks import DetectionTracks
from uav_tui.hosting.wire import FrameOutcome
from uav_tui.stats import PipelineStats, RollingStats

if TYPE_CHECKING:
    from uav_values.camera import CameraModel

logger = logging.getLogger(__name__)

JOIN_TIMEOUT_S = 2.0
"""How long stopping waits for the processor's current call before abandoning it."""


class ThreadHost(DeliversResults):
    """Runs a processor on one dedicated thread, always on the newest frame of a buffer.

    The thread waits on the frame buffer itself, processes the newest frame and posts the result to
    the event loop without waiting for it, so the only hand-off on the per-frame path is capture ->
    processor. Frames that arrive meanwhile replace each other, so a slow processor skips frames and
    never queues them. ``call`` runs an operator command (``catch_cmd``, ``customize_processing``) on
    the same thread between two frames, so researchers never need a lock.

    This is ``isolation = "thread"``: a breakpoint in the processor works, but a processor that holds
    the GIL, hangs or crashes takes the platform with it (see :class:`~uav_tui.hosting.process_host.SubprocessHost`).
    """

    isolation = Isolation.THREAD

    def __init__(self, processor: LoadedProcessor, on_result: Callable[[ProcessedFrame], None], *,
                 save_max_hz: float = DEFAULT_SAVE_MAX_HZ, events: EventLog | None = None) -> None:
        self.processor = processor
        self.events = events
        """Where the count of the processor's log records left out is said (None: logged)."""
        self.save_max_hz = save_max_hz
        self.telemetry: TelemetryManager | None = None
        self.tm: FrameTelemetry | None = None
        """The processor's ``tmMgr`` once :meth:`bind_telemetry` made it (a reload hands it to the new instance)."""
        self._fields: tuple[Telemetry | None, dict[str, Any]] = (None, {})
        """The telemetry last given to the processor and its fields as a dict (telemetry changes slower than frames)."""
        self.stats = RollingStats()
        self.stage_clock: StageClock | None = None
        """Set in a replay: moves a result's stage times onto the replay's clock (before they are counted)."""
        self.current: Frame | None = None
        """The frame being processed (read on the processor thread by ``tmMgr.save``); None between frames."""
        self.last: ProcessedFrame | None = None
        """The newest finished frame."""
        self.consecutive_errors = 0
        self._on_result = on_result
        self._wake = threading.Condition()
        self._jobs: deque[tuple[Callable[[], Any], Future[Any]]] = deque()
        self._buffer: FrameBuffer | None = None
        self._stopping = False
        self._thread: threading.Thread | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._busy_since_ns: int | None = None
        self._tracks = DetectionTracks()

    # -- loop side -------------------------------------------------------------------------------

    def bind_telemetry(self, telemetry: TelemetryManager) -> None:
        """Give the processor its ``tmMgr``: the telemetry at each frame's capture; ``telemetry`` stores saves."""
        self.telemetry = telemetry
        self.tm = FrameTelemetry(lambda image, extra: telemetry.save(image, **extra), save_max_hz=self.save_max_hz)
        self.processor.instance.tmMgr = self.tm

    def attach(self, buffer: FrameBuffer, camera: CameraModel | None = None) -> None:
        """Take frames from ``buffer`` from now on (a new source, with ``camera`` its model for ``tmMgr.camera()``)."""
        if self.tm is not None:
            self.tm.camera_model = camera
        with self._wake:
            if self._buffer is not None:
                self._buffer.remove_listener(self._on_frame)
            self._buffer = buffer
            buffer.add_listener(self._on_frame)
            self._wake.notify()

    async def run(self) -> None:
        """Start the processor thread and keep it running until cancelled."""
        if self._thread is not None:
            raise RuntimeError("ThreadHost.run() is already running")
        self._loop = asyncio.get_running_loop()
        self._thread = threading.Thread(target=self._thread_main, name="processor", daemon=True)
        logs = ThreadLogBudget(self._thread, self._say_left_out)
        logs.install()  # before the thread's first record: installed after its start, a frame's records passed
        self._thread.start()
        try:
            await asyncio.Event().wait()
        finally:
            self.close()
            try:
                # Let the current call finish before the interpreter exits: OpenCV aborts the process when its
                # code is still running in a thread at shutdown. A hung processor is abandoned after the wait.
                await asyncio.get_running_loop().run_in_executor(None, self._thread.join, JOIN_TIMEOUT_S)
            finally:  # a wait cancelled too (a loop shutting down) must not leave the filter on the handlers
                logs.remove()

    def _say_left_out(self, count: int) -> None:
        text = f"{count} more log records of the processor left out (too many at once)"
        if self.events is not None:
            self.events.emit("warning", "processor", text)
        else:
            logger.warning("%s", text)

    async def call(self, method: str, *args: Any) -> Answer:
        """Call ``processor.<method>(*args)`` on the processor thread; its exception propagates."""
        bound = getattr(self.processor.instance, method)

        def answer() -> Answer:
            taken = time.monotonic_ns()
            return Answer(bound(*args), taken)
        return await self._submit(answer)

    async def replace(self, processor: LoadedProcessor) -> LoadedProcessor:
        """Swap in another processor between two frames; returns the old one."""
        def swap() -> LoadedProcessor:
            old, self.processor = self.processor, processor
            return old
        old = await self._submit(swap)
        self.consecutive_errors = 0  # on the loop, after the old processor's results (posted before the swap)
        return old

    async def reload(self) -> ProcessorInfo:
        """Re-import the processor's code and swap the new instance in; a load error keeps the old one."""
        current = self.processor
        fresh = await asyncio.get_running_loop().run_in_executor(None, functools.partial(
            load_processor, current.spec, current.kwargs, fresh=True))
        fresh.instance.tmMgr = self.tm
        await self.replace(fresh)
        return fresh.info

    def state(self) -> ProcessorState:
        return ProcessorState(self.isolation, HostPhase(HostState.RUNNING), os.getpid(), None)

    def snapshot(self) -> PipelineStats:
        captured = self._buffer.captured if self._buffer is not None else 0
        return self.stats.snapshot(captured, self._busy_since_ns)

    @property
    def saves_throttled(self) -> int:
        """``tmMgr.save`` calls its ``tmMgr`` dropped above ``save_max_hz``."""
        return self.tm.saves_throttled if self.tm is not None else 0

    @property
    def busy_s(self) -> float:
        """Seconds the current call into the processor has been running (0 when idle)."""
        since = self._busy_since_ns
        return (time.monotonic_ns() - since) / 1e9 if since else 0.0

    def close(self) -> None:
        """Stop taking frames; the thread ends after its current call (a hung processor is abandoned)."""
        with self._wake:
            self._stopping = True
            if self._buffer is not None:
                self._buffer.remove_listener(self._on_frame)
            jobs, self._jobs = list(self._jobs), deque()
            self._wake.notify()
        for _, future in jobs:
            future.cancel()

    def _submit(self, job: Callable[[], Any]) -> asyncio.Future[Any]:
        if self._stopping:
            raise RuntimeError("the processor worker is closed")
        future: Future[Any] = Future()
        with self._wake:
            self._jobs.append((job, future))
            self._wake.notify()
        return asyncio.wrap_future(future)

    def _on_frame(self, frame: Frame) -> None:  # capture thread
        with self._wake:
            self._wake.notify()

    # -- processor thread ------------------------------------------------------------------------

    def _thread_main(self) -> None:
        last_seq, last_buffer = 0, None
        while True:
            with self._wake:
                self._wake.wait_for(functools.partial(self._ready, last_seq, last_buffer))
                if self._stopping:
                    return
                job = self._jobs.popleft() if self._jobs else None
                buffer = self._buffer
            if job is not None:
                _run_job(*job)
                continue
            assert buffer is not None
            if buffer is not last_buffer:
                last_seq, last_buffer = 0, buffer
            frame = buffer.latest()
            if frame is None or frame.seq <= last_seq:
                continue
            last_seq = frame.seq
            outcome = self._process(frame)
            loop = self._loop
            if loop is not None and not loop.is_closed():
                loop.call_soon_threadsafe(self._deliver, frame, outcome)

    def _ready(self, seq: int, buffer: FrameBuffer | None) -> bool:
        """Something for the processor thread: a stop, a job, or a frame newer than ``seq`` of ``buffer``."""
        return self._stopping or bool(self._jobs) or self._has_newer(seq, buffer)

    def _has_newer(self, seq: int, buffer: FrameBuffer | None) -> bool:
        if self._buffer is None:
            return False
        if self._buffer is not buffer:
            return True
        return self._buffer.newest_seq > seq

    def _process(self, frame: Frame) -> FrameOutcome:
        self._busy_since_ns = time.monotonic_ns()
        self.current = frame
        self._begin(frame)
        try:
            capabilities = self.processor.info.capabilities
            return call_frame(self.processor.instance, frame.image, vector="getPreparedVector" in capabilities,
                              outputs=output_methods(capabilities), frame_seq=frame.seq, tracks=self._tracks,
                              seen_ns=frame.t_mono_ns)
        finally:
            self._busy_since_ns = None
            self.current = None

    def _begin(self, frame: Frame) -> None:
        """Tell the processor's ``tmMgr`` which frame it is processing and the telemetry at its capture."""
        tm = self.tm
        if self.telemetry is None or tm is None:
            return
        telemetry, heartbeat_age = self.telemetry.at(frame.t_mono_ns)
        if telemetry is not self._fields[0]:
            self._fields = (telemetry, {name: getattr(telemetry, name) for name in TELEMETRY_FIELDS
                                        if name != "heartbeat_age_s"})
        tm.begin(frame.seq, frame.t_mono_ns, frame.t_wall_ns, self._fields[1], heartbeat_age)


async def load_in_thread(spec: str, kwargs: dict[str, Any]) -> LoadedProcessor:
    """``load_processor`` on a daemon thread of its own: when the wait is cancelled (Ctrl-C or SIGTERM while a slow
    ``__init__`` runs), the thread is left behind and does not hold the process's exit, as an executor's would."""
    loop = asyncio.get_running_loop()
    future: asyncio.Future[LoadedProcessor] = loop.create_future()

    def run() -> None:
        try:
            outcome: tuple[LoadedProcessor | None, BaseException | None] = (load_processor(spec, kwargs), None)
        except BaseException as exc:  # noqa: BLE001 - handed to the awaiting caller
            outcome = (None, exc)
        with contextlib.suppress(RuntimeError):  # the loop is closed: nobody waits
            loop.call_soon_threadsafe(_settle, future, *outcome)

    threading.Thread(target=run, name="processor-loader", daemon=True).start()
    return await future


def _settle(future: asyncio.Future[Any], result: Any, error: BaseException | None) -> None:
    if future.done():  # cancelled
        return
    if error is not None:
        future.set_exception(error)
    else:
        future.set_result(result)


def _run_job(job: Callable[[], Any], future: Future[Any]) -> None:
    if not future.set_running_or_notify_cancel():
        return
    try:
        future.set_result(job())
    except BaseException as exc:  # noqa: BLE001 - handed to the awaiting caller
        future.set_exception(exc)
