"""The process host (``isolation = "process"``): the processor in its own process, same surface as
:class:`~uav_tui.hosting.thread_host.ThreadHost`, nothing shared.

:class:`SubprocessHost` joins three parts, each in a module of its own: frame feeding
(:class:`~uav_tui.hosting.frame_feeder.FrameFeeder`: shared-memory frames offered in the child's mailbox), the
link to the child (:class:`~uav_tui.hosting.child_link.ChildLink`: messages of :mod:`uav_tui.hosting.wire` down
and up its pipe), and the watchdog and restarts (:class:`~uav_tui.hosting.supervisor.ChildSupervisor`). What is
left here is the host's surface and what becomes of a result.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from processors import LoadedProcessor
from processors.base import ProcessorInfo
from processors.frame_telemetry import DEFAULT_SAVE_MAX_HZ
from sources.buffer import Frame, FrameBuffer
from uav_tui.config import Isolation
from uav_tui.errors import UavError
from uav_tui.events import EventLog
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.hosting.child_link import ChildLink
from uav_tui.hosting.child_process import ChildProcess, rss_mb
from uav_tui.hosting.codec import UnreadableResult
from uav_tui.hosting.frame_feeder import FrameFeeder
from uav_tui.hosting.host import Answer, DeliversResults, HostPhase, ProcessedFrame, ProcessorState, StageClock
from uav_tui.hosting.supervisor import ChildSupervisor
from uav_tui.hosting.wire import FrameOutcome, Result, ResultHead, Save
from uav_tui.stats import PipelineStats, RollingStats

if TYPE_CHECKING:
    from uav_values.camera import CameraModel


class SubprocessHost(DeliversResults):
    """Runs a processor in a child process, always on the newest frame of a buffer.

    Create with :meth:`start` (loads the processor in its process; raises ProcessorLoadError).

    Args:
        spec, kwargs: the processor to load (as ``load_processor``), again at every restart.
        on_result: called on the loop with every processed frame.
        events: where crashes, restarts and give-ups are reported.
        on_fault: called on the loop with the reason when the child dies or is killed (stop autonomy).
        timeout_s: a frame or call unanswered this long gets the child killed and restarted.
        memory_mb: the child's address-space cap (RLIMIT_AS), None for none.
        save_images: False when the platform does not record: ``tmMgr.save`` in the child then sends its columns
            but not its image (which would be copied and piped here only to be dropped).
        save_max_hz: ``tmMgr.save`` calls kept per second of frame time (the rest are dropped in the child).
        first_backoff_s: the wait before the first restart; it doubles with each one.
    """

    isolation = Isolation.PROCESS

    def __init__(self, spec: str, kwargs: dict[str, Any], on_result: Callable[[ProcessedFrame], None], *,
                 events: EventLog, on_fault: Callable[[str], None], timeout_s: float = 5.0,
                 memory_mb: float | None = None, save_images: bool = True,
                 save_max_hz: float = DEFAULT_SAVE_MAX_HZ, first_backoff_s: float = 1.0) -> None:
        self.spec, self.kwargs = spec, dict(kwargs)
        self.stats = RollingStats()
        self.stage_clock: StageClock | None = None
        """Set in a replay: moves a result's stage times onto the replay's clock (before they are counted)."""
        self.current: Frame | None = None
        """The frame whose ``tmMgr.save`` requests are being stored (None between frames)."""
        self.last: ProcessedFrame | None = None
        self.consecutive_errors = 0
        self.saves_throttled = 0
        """``tmMgr.save`` calls the children dropped above ``save_max_hz`` (every child, restarts included)."""
        self.telemetry: TelemetryManager | None = None
        self.events = events
        self.timeout_s = timeout_s
        self._on_result = on_result
        self._running = False
        self._link = ChildLink(spec, self)
        self._feeder = FrameFeeder(spec, events, self._link)
        self._supervisor = ChildSupervisor(
            spec, self.kwargs, link=self._link, feeder=self._feeder, events=events, on_fault=on_fault,
            timeout_s=timeout_s, memory_mb=memory_mb, save_images=save_images, save_max_hz=save_max_hz,
            first_backoff_s=first_backoff_s)

    @classmethod
    async def start(cls, spec: str, kwargs: dict[str, Any], on_result: Callable[[ProcessedFrame], None],
                    **options: Any) -> SubprocessHost:
        """Start the child and wait until the processor is constructed (ProcessorLoadError if it cannot be)."""
        worker = cls(spec, kwargs, on_result, **options)
        try:
            worker._supervisor.adopt(await worker._supervisor.start_child())
        except BaseException:
            worker.close()
            raise
        return worker

    @property
    def processor(self) -> LoadedProcessor:
        """What was loaded; ``instance`` is None: the object lives in the child."""
        return self._supervisor.processor

    @property
    def phase(self) -> HostPhase:
        """Starting, running, restarting N, crashed (and why, once the restarts gave up)."""
        return self._supervisor.phase

    def bind_telemetry(self, telemetry: TelemetryManager) -> None:
        """Attach the telemetry at each frame's capture to it as it is handed over; store ``tmMgr.save`` through it."""
        self.telemetry = self._feeder.telemetry = telemetry

    def attach(self, buffer: FrameBuffer, camera: CameraModel | None = None) -> None:
        """Take frames from ``buffer`` from now on (a new source, with ``camera`` its model for ``tmMgr.camera()``)."""
        self._feeder.attach(buffer, camera)

    async def run(self) -> None:
        """The watchdog: kill a child silent for longer than ``timeout_s``; until cancelled, then stop all."""
        if self._running:
            raise RuntimeError("SubprocessHost.run() is already running")
        self._running = True
        try:
            await self._supervisor.watch()
        finally:
            self.close()
            await asyncio.get_running_loop().run_in_executor(None, self._let_go, 2.0)

    def _let_go(self, timeout: float) -> None:
        """After :meth:`close`: wait until the feeder thread has left and every child was reaped, so that nothing of
        theirs (a slot being copied into, a pipe, an output reader) outlives the host."""
        deadline = time.monotonic() + timeout
        self._feeder.join(timeout)
        self._supervisor.reap(max(0.0, deadline - time.monotonic()))

    async def call(self, method: str, *args: Any) -> Answer:
        """Call ``processor.<method>(*args)`` in the child; raises ProcessorRaised if it raised there.

        A call still unanswered from before makes this one fail at once (UavError): commands never
        queue behind a hung processor. The caller bounds the wait (``processor_call_timeout``).
        """
        child = self._supervisor.running_child()
        overdue = [c for c in child.calls.values() if c.future.done()]
        if overdue:
            waited = (time.monotonic_ns() - overdue[0].sent_ns) / 1e9
            raise UavError(f"the processor has not returned from {overdue[0].what} for {waited:.1f} s; it is "
                           f"restarted after processor_timeout = {self.timeout_s:g} s")
        answer = self._link.call(child, method, args)
        if answer is None:
            raise UavError(f"the processor is not running ({self.phase})")
        return await answer

    async def reload(self) -> ProcessorInfo:
        """Start a new child with the code as it is now; swap only once it loaded (else the old one keeps running)."""
        info = await self._supervisor.replace()
        self.consecutive_errors = 0
        return info

    def snapshot(self) -> PipelineStats:
        child = self._supervisor.child
        return self.stats.snapshot(self._feeder.captured, child.busy_since_ns() if child is not None else None)

    @property
    def busy_s(self) -> float:
        """Seconds the oldest unanswered frame or call has been with the child (0 when idle)."""
        child = self._supervisor.child
        since = child.busy_since_ns() if child is not None else None
        return (time.monotonic_ns() - since) / 1e9 if since else 0.0

    def state(self) -> ProcessorState:
        child = self._supervisor.child
        pid = child.pid if child is not None else None
        return ProcessorState(self.isolation, self.phase, pid, rss_mb(pid) if pid else None)

    def close(self) -> None:
        """Stop taking frames and kill every child at once (whatever the processor is doing). Idempotent."""
        self._feeder.stop()
        self._supervisor.close()
        self._feeder.close(self._supervisor.children)

    # -- what the child sends back (on the loop; :class:`~uav_tui.hosting.child_link.TakesResults`) ---------------

    def take_result(self, child: ChildProcess, message: Result) -> None:
        """A frame's result: its slots freed, its saves stored, its outcome delivered as it arrived."""
        self.saves_throttled += message.saves_throttled  # dropped in the child, whatever became of the frame
        frame = self._feeder.take(child, message)
        if frame is None:
            return
        outcome = message.outcome
        self._store(message.saves, frame)
        if outcome.detections:
            self._supervisor.next_track_id = max(self._supervisor.next_track_id, 1 + max(
                (found.track_id for found in outcome.detections if found.track_id is not None), default=-1))
        self._deliver(frame, outcome)

    def take_unreadable(self, child: ChildProcess, unreadable: UnreadableResult) -> None:
        """A result whose outputs did not decode: that frame's error, its slots freed, nothing of it used."""
        head = unreadable.head
        assert isinstance(head, ResultHead)
        times = head.outcome
        error = f"the processor's outputs could not be read: {unreadable.reason}"
        self.take_result(child, Result(head.gen, head.released, head.saves_throttled, FrameOutcome(
            times.t_start_ns, times.t_end_ns, times.t_vector_ns, error=error), ()))

    def take_spent(self, child: ChildProcess, saves: tuple[Save, ...], released: tuple[str, ...]) -> None:
        """A reply's slots let go and its ``tmMgr.save`` calls."""
        self._feeder.release(child, released)
        self._store(saves, None)

    def _store(self, saves: tuple[Save, ...], frame: Frame | None) -> None:
        """Replay the child's ``tmMgr.save`` calls of ``frame`` here, where the recorder is."""
        if not saves or self.telemetry is None:
            return
        self.current = frame
        try:
            for save in saves:
                try:
                    self.telemetry.save(save.image, **save.extra)
                except (TypeError, ValueError) as exc:  # what the recorder refuses costs that save alone
                    self.events.emit("error", "processor", f"a tmMgr.save from the processor was refused: {exc}")
        finally:
            self.current = None
