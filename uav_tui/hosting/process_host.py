"""The process host (``isolation = "process"``): the processor in its own process, same surface as
:class:`~uav_tui.hosting.thread_host.ProcessorWorker`, nothing shared.

Frames live in :class:`~uav_tui.hosting.frame_ring.FrameRing`'s shared-memory slots (decoded there by cameras
that can; copied in once, off the capture thread, for those that cannot; never pickled). Every new frame
is *offered* in the child's :class:`~uav_tui.hosting.frame_mailbox.FrameMailbox`, replacing the previous offer,
and the child claims the newest whenever it is free: the hand-off waits for nothing in this process.
Results, calls and ``tmMgr.save`` requests come over a pipe (messages in :mod:`uav_tui.hosting.wire`), read
by the event loop itself whenever the pipe is readable, never blocking it. The watchdog
(``run``, on the loop) kills a child that stays silent longer than ``processor_timeout``; a child that
dies for any reason is reported (exit code or signal, last lines of its output), ``on_fault`` stops
autonomy, and a fresh child with the same arguments is started after 1, 2, 4 ... s, at most
:data:`MAX_RESTARTS` times a minute. Whenever a child is killed or ends, so do the processes it started
(its process group).
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import itertools
import logging
import pickle
import threading
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, Any

import numpy as np

from controllers.base import TELEMETRY_FIELDS
from processors import LoadedProcessor
from processors.base import ProcessorInfo
from processors.errors import ProcessorLoadError
from processors.frame_telemetry import DEFAULT_SAVE_MAX_HZ
from sources.buffer import Frame, FrameBuffer
from uav_tui.errors import UavError
from uav_tui.events import EventLog
from uav_tui.hosting.child_process import ChildProcess, Offered, PendingCall, describe_exit, rss_mb, say_output, spawn
from uav_tui.hosting.frame_mailbox import TELEMETRY_BYTES, MailboxGone, Offer
from uav_tui.hosting.frame_ring import FrameRing
from uav_tui.hosting.host import Answer, ProcessedFrame, ProcessorState
from uav_tui.hosting.wire import Call, Camera, Forget, Load, LoadError, Ready, Reply, Result, Save, ToChild
from uav_tui.line_budget import LineBudget
from uav_tui.stats import PipelineStats, RollingStats
from uav_tui.telemetry import TelemetryManager

if TYPE_CHECKING:
    from sources.camera_model import CameraModel

logger = logging.getLogger(__name__)

WATCH_PERIOD_S = 0.05
LOAD_TIMEOUT_S = 60.0
"""A processor that takes longer to import and construct is killed (YOLO on a Pi needs a few seconds)."""
MAX_RESTARTS = 5
"""Restarts allowed within :data:`RESTART_WINDOW_S`; one more crash and the platform gives up."""
RESTART_WINDOW_S = 60.0


class ProcessorRaised(Exception):
    """The researcher's method raised in the child; the message is ``Type: message``."""


RESULTS_POLL_S = 0.001
"""The child's messages that come closer together than this (a replay's results, never a camera's) are read this
often, in batches, instead of each waking the event loop: the child's write then wakes nobody. Messages further
apart are read as they arrive. A result frees its frame's slot, so a poll period passes at most ``MAX_SLOTS`` frames.
(Template matching on a generated 640x480 replay: CPU a frame 1.13x -> 1.09x the bare loop.)"""


class ProcessWorker:
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

    isolation = "process"

    def __init__(self, spec: str, kwargs: dict[str, Any], on_result: Callable[[ProcessedFrame], None], *,
                 events: EventLog, on_fault: Callable[[str], None], timeout_s: float = 5.0,
                 memory_mb: float | None = None, save_images: bool = True,
                 save_max_hz: float = DEFAULT_SAVE_MAX_HZ, first_backoff_s: float = 1.0) -> None:
        self.spec, self.kwargs = spec, dict(kwargs)
        self.processor = LoadedProcessor(instance=None, info=ProcessorInfo(spec, None, frozenset()), spec=spec,
                                         kwargs=self.kwargs)
        """What was loaded; ``instance`` is None: the object lives in the child."""
        self.stats = RollingStats()
        self.stage_clock: Callable[[ProcessedFrame], None] | None = None
        """Set in a replay: moves a result's stage times onto the replay's clock (before they are counted)."""
        self.current: ProcessedFrame | None = None
        """The frame whose ``tmMgr.save`` requests are being stored (None between frames)."""
        self.last: ProcessedFrame | None = None
        self.consecutive_errors = 0
        self.hand_over_failures = 0
        """Frames that could not be handed to the child (a platform fault; the first is logged)."""
        self.telemetry: TelemetryManager | None = None
        self.events = events
        self.timeout_s = timeout_s
        self.memory_mb = memory_mb
        self.save_images = save_images
        self.save_max_hz = save_max_hz
        self.first_backoff_s = first_backoff_s
        self.state_text = "starting"
        self._on_result = on_result
        self._on_fault = on_fault
        self._lock = threading.RLock()
        self._send_lock = threading.Lock()
        self._wake = threading.Condition(self._lock)
        self._offer_made = threading.Condition(self._lock)
        self._nudged = False
        self._starved = False
        """A frame found every slot held: the next slot freed nudges the feeder."""
        self._ring = FrameRing(on_free=self._on_slot_free, on_unlink=self._forget)
        self._to_forget: list[str] = []
        self._child: ChildProcess | None = None
        self._buffer: FrameBuffer | None = None
        self._camera: CameraModel | None = None
        """The camera model of ``_buffer``'s source, sent to each child (``tmMgr.camera()``)."""
        self._picked: tuple[FrameBuffer | None, int] = (None, 0)
        """The newest frame taken for an offer (each frame is offered once)."""
        self._offered: tuple[FrameBuffer | None, int, int] = (None, 0, 0)
        """The newest frame put in the mailbox, and its gen (an older frame is never put after it)."""
        self._pickled_telemetry: tuple[object, bytes] = (None, b"")
        """The newest telemetry update and its pickled fields."""
        self._loop: asyncio.AbstractEventLoop | None = None
        self._call_ids = itertools.count(1)
        self._gens = itertools.count(1)
        self._restarts: deque[float] = deque()
        self._restart_task: asyncio.Task[None] | None = None
        self._all_children: list[ChildProcess] = []
        self._closing = False
        self._running = False
        # Children are started from this one long-lived thread: the child's parent-death signal
        # (PR_SET_PDEATHSIG) fires when the *thread* that started it ends, not only the process.
        self._spawner = ThreadPoolExecutor(1, thread_name_prefix="processor-spawner")
        self._output: LineBudget[bytes] = LineBudget(say_output, self._say_left_out)
        """What the processor prints or logs (any of its children): a burst, then a line a second, and a count."""
        threading.Thread(target=self._feed, name=f"processor-feeder({spec})", daemon=True).start()

    @classmethod
    async def start(cls, spec: str, kwargs: dict[str, Any], on_result: Callable[[ProcessedFrame], None],
                    **options: Any) -> ProcessWorker:
        """Start the child and wait until the processor is constructed (ProcessorLoadError if it cannot be)."""
        worker = cls(spec, kwargs, on_result, **options)
        worker._loop = asyncio.get_running_loop()
        try:
            worker._adopt(await worker._start_child())
        except BaseException:
            worker.close()
            raise
        return worker

    # -- the common worker surface ---------------------------------------------------------------

    def bind_telemetry(self, telemetry: TelemetryManager) -> None:
        """Attach the telemetry at each frame's capture to it as it is handed over; store ``tmMgr.save`` through it."""
        self.telemetry = telemetry

    def attach(self, buffer: FrameBuffer, camera: CameraModel | None = None) -> None:
        """Take frames from ``buffer`` from now on (a new source, with ``camera`` its model for ``tmMgr.camera()``)."""
        with self._lock:
            if self._buffer is not None:
                self._detach(self._buffer)
            self._buffer, self._camera, child = buffer, camera, self._child
        if child is not None:
            self._send(child, Camera(camera))  # before the first frame of the new source is offered
        with self._lock:
            buffer.set_allocator(self._ring.capture_view)  # cameras that can decode into shared memory do
            buffer.set_read_waiter(functools.partial(self._wait_claimed, buffer))
            buffer.add_listener(self._on_frame)
        self._nudge()

    def _detach(self, buffer: FrameBuffer) -> None:
        buffer.remove_listener(self._on_frame)
        buffer.set_allocator(None)
        buffer.set_read_waiter(None)

    async def run(self) -> None:
        """The watchdog: kill a child silent for longer than ``timeout_s``; until cancelled, then stop all."""
        if self._running:
            raise RuntimeError("ProcessWorker.run() is already running")
        self._running = True
        try:
            while True:
                await asyncio.sleep(WATCH_PERIOD_S)
                child = self._child
                busy = self.busy_s
                if child is not None and busy > self.timeout_s and not child.kill_reason:
                    child.kill(f"no answer for {busy:.1f} s (processor_timeout = {self.timeout_s:g} s): killed")
        finally:
            self.close()
            await asyncio.get_running_loop().run_in_executor(None, self._reap, 2.0)

    async def call(self, method: str, *args: Any) -> Answer:
        """Call ``processor.<method>(*args)`` in the child; raises ProcessorRaised if it raised there.

        A call still unanswered from before makes this one fail at once (UavError): commands never
        queue behind a hung processor. The caller bounds the wait (``processor_call_timeout``).
        """
        child = self._running_child()
        overdue = [c for c in child.calls.values() if c.future.done()]
        if overdue:
            waited = (time.monotonic_ns() - overdue[0].sent_ns) / 1e9
            raise UavError(f"the processor has not returned from {overdue[0].what} for {waited:.1f} s; it is "
                           f"restarted after processor_timeout = {self.timeout_s:g} s")
        call_id = next(self._call_ids)
        future: asyncio.Future[Any] = asyncio.get_running_loop().create_future()
        child.calls[call_id] = PendingCall(f"{method}{args!r}", time.monotonic_ns(), future)
        if not self._send(child, Call(call_id, method, args)):
            child.calls.pop(call_id)
            raise UavError(f"the processor is not running ({self.state_text})")
        return await future

    async def reload(self) -> ProcessorInfo:
        """Start a new child with the code as it is now; swap only once it loaded (else the old one keeps running)."""
        fresh = await self._start_child()
        if self._restart_task is not None:  # the operator's fixed code replaces a crashed processor's restarts
            self._restart_task.cancel()
            self._restarts.clear()
        old = self._child
        self._adopt(fresh)
        if old is not None:
            self._retire(old, "replaced by a reload")
        self.consecutive_errors = 0
        return fresh.ready.result()

    def snapshot(self) -> PipelineStats:
        captured = self._buffer.captured if self._buffer is not None else 0
        child = self._child
        return self.stats.snapshot(captured, child.busy_since_ns() if child is not None else None)

    @property
    def busy_s(self) -> float:
        """Seconds the oldest unanswered frame or call has been with the child (0 when idle)."""
        child = self._child
        since = child.busy_since_ns() if child is not None else None
        return (time.monotonic_ns() - since) / 1e9 if since else 0.0

    def state(self) -> ProcessorState:
        child = self._child
        pid = child.pid if child is not None else None
        return ProcessorState(self.isolation, self.state_text, pid, rss_mb(pid) if pid else None)

    def close(self) -> None:
        """Stop taking frames and kill every child at once (whatever the processor is doing). Idempotent."""
        with self._wake:
            self._closing = True
            if self._buffer is not None:
                self._detach(self._buffer)
            self._wake.notify()
        if self._restart_task is not None:
            self._restart_task.cancel()
        for child in self._all_children:
            child.kill("stopped")  # reaped by its exit watch's thread, not the loop's executor (a failed start ends it)
            self._hang_up(child)
            for call in child.calls.values():
                if not call.future.done():
                    call.future.cancel()
        with self._lock:  # no offer is being made: they check _closing under this lock
            for child in self._all_children:
                child.mailbox.close()
        self._ring.close()
        self._spawner.shutdown(wait=False)
        self._output.close()

    # -- children --------------------------------------------------------------------------------

    async def _start_child(self) -> ChildProcess:
        loop = self._loop = asyncio.get_running_loop()
        child = await loop.run_in_executor(self._spawner, spawn, loop.create_future(), self._output.lines)
        self._all_children.append(child)
        child.watch_exit(functools.partial(_call_soon, loop, self._ended, child))
        loop.add_reader(child.inbox.fileno(), self._on_readable, child)
        self._send(child, Load(self.spec, self.kwargs, self.memory_mb, self.save_images, self.save_max_hz))
        try:
            await asyncio.wait_for(asyncio.shield(child.ready), LOAD_TIMEOUT_S)
        except TimeoutError:
            _abandon(child)
            raise ProcessorLoadError(f"{self.spec} did not finish loading within {LOAD_TIMEOUT_S:g} s",
                                     class_name=self.spec.rpartition(":")[2]) from None
        except BaseException:
            _abandon(child)
            raise
        return child

    def _say_left_out(self, count: int) -> None:
        self.events.emit("warning", "processor", f"{count} more lines of the processor's output left out (too many at "
                         "once; the crash report has the last ones)")

    def _adopt(self, child: ChildProcess) -> None:
        info = child.ready.result()
        self.processor = LoadedProcessor(instance=None, info=info, spec=self.spec, kwargs=self.kwargs)
        if self._camera is not None:  # before it can be offered a frame
            self._send(child, Camera(self._camera))
        with self._lock:
            self._child = child
            self._picked, self._offered = (None, 0), (None, 0, 0)
        self.state_text = "running"
        self._nudge()

    def _retire(self, child: ChildProcess, why: str) -> None:
        child.kill(why)
        for call in child.calls.values():
            if not call.future.done():
                call.future.set_exception(UavError(f"{call.what} not answered: the processor was {why}"))

    def _running_child(self) -> ChildProcess:
        child = self._child
        if child is None or child.ended.is_set():
            raise UavError(f"the processor is not running ({self.state_text})")
        return child

    # -- frames (the feeder thread; anyone may nudge it) -----------------------------------------

    def _on_frame(self, frame: Frame) -> None:
        self._try_offer(may_copy=False)  # capture thread: a frame captured into a slot is offered at once

    def _nudge(self) -> None:
        """Wake the feeder: a frame to copy arrived, a starved frame found a free slot, a child started."""
        with self._wake:
            self._nudged = True
            self._wake.notify()

    def _on_slot_free(self) -> None:
        with self._lock:
            starved, self._starved = self._starved, False
        if starved:
            self._nudge()

    def _feed(self) -> None:
        """The feeder thread: copies the newest frame into a slot (when it was not captured into one) and offers it.

        The copy runs here, not on the capture thread, so the camera decodes its next frame meanwhile.
        """
        while True:
            with self._wake:
                self._wake.wait_for(lambda: self._nudged or self._closing)
                if self._closing:
                    return
                self._nudged = False
            self._try_offer(may_copy=True)

    def _try_offer(self, *, may_copy: bool) -> None:
        try:
            self._offer_newest(may_copy=may_copy)
        except Exception as exc:  # a bug here must not stop the camera: say so once, go on
            self.hand_over_failures += 1
            if self.hand_over_failures == 1:
                logger.exception("ProcessWorker(%s): handing a frame over failed (logged once)", self.spec)
                self.events.emit("error", "processor", f"frames cannot be handed to the processor: {exc!r}")

    def _offer_newest(self, *, may_copy: bool) -> None:
        """Offer the newest frame to the child, replacing the previous offer, if it was not offered yet.

        A frame captured into a slot is offered from whichever thread noticed (no copy, no thread switch);
        one that must be copied is left to the feeder thread (``may_copy``), off the capture thread.
        """
        with self._lock:
            child, buffer = self._child, self._buffer
            if self._closing or child is None or buffer is None or self._picked == (buffer, buffer.newest_seq):
                return
            frame = buffer.peek()  # read once the child claimed it (a replay then puts the next)
            if frame is None:
                return
            slot = self._ring.take_for_child(frame.image)
            copied = slot is None
            if copied and not may_copy:
                self._nudged = True
                self._wake.notify()
                return
            slot = slot or self._ring.acquire(frame.image.shape)
            if slot is None:
                self._starved = True  # every slot held: not picked; a newer frame or a freed slot tries again
                return
            self._picked = (buffer, frame.seq)
            forget, self._to_forget = self._to_forget, []
        if copied:
            np.copyto(slot.array(), frame.image)  # the slot is ours alone until it is offered
        if forget:
            self._send(child, Forget(forget))
        offer = Offer(next(self._gens), slot.name, slot.shape, frame.seq, frame.t_mono_ns, frame.t_wall_ns,
                      *self._telemetry_at(frame.t_mono_ns))
        with self._lock:
            current = child is self._child and not self._closing
            if current and self._offered[0] is buffer and self._offered[1] >= frame.seq:
                current = False  # a newer frame was offered while this one was copied
            if current:
                try:
                    previous, taken = child.mailbox.offer(offer)
                except MailboxGone:
                    current = False  # the child is gone: its exit is being reported
            if not current:
                unused = [slot]
            else:
                self._offered = (buffer, frame.seq, offer.gen)
                self._offer_made.notify_all()
                child.offered[offer.gen] = Offered(buffer, frame, slot, copied)
                child.held[slot.name] = slot
                replaced = None if taken else child.offered.pop(previous, None)
                unused = [child.held.pop(replaced.slot.name)] if replaced is not None else []
        for stale in unused:
            self._ring.release_child(stale)

    def _wait_claimed(self, buffer: FrameBuffer, seq: int, timeout_s: float) -> bool:
        """``buffer``'s read waiter: block until the child claimed frame ``seq`` (True) or ``timeout_s`` passed.

        A replay paced by its reader then puts its next frame while the child still works on this one.
        """
        deadline = time.monotonic() + timeout_s
        with self._offer_made:
            if not self._was_offered(buffer, seq) and not self._offer_made.wait_for(
                    lambda: self._was_offered(buffer, seq), timeout_s):
                return False
            child, gen = self._child, self._offered[2]
        if child is not None:
            with contextlib.suppress(MailboxGone):
                return child.mailbox.wait_claimed(gen, max(0.0, deadline - time.monotonic()))
        time.sleep(max(0.0, deadline - time.monotonic()))  # no child, or it died: its successor is offered the frame
        return False

    def _was_offered(self, buffer: FrameBuffer, seq: int) -> bool:
        return self._offered[0] is buffer and self._offered[1] >= seq

    def _telemetry_at(self, t_mono_ns: int) -> tuple[bytes, float | None]:
        """The telemetry attached to a frame: the newest update received by its capture pickled, the heartbeat age now.

        The update is pickled once, when it arrives; frames come faster than telemetry. Empty without a
        telemetry manager.
        """
        if self.telemetry is None:
            return b"", None
        latest, heartbeat_age = self.telemetry.at(t_mono_ns)
        if latest is not self._pickled_telemetry[0]:
            data = pickle.dumps({name: getattr(latest, name) for name in TELEMETRY_FIELDS
                                 if name != "heartbeat_age_s"})
            if len(data) > TELEMETRY_BYTES:  # never seen: the fields are numbers and short names
                logger.warning("ProcessWorker: telemetry of %d bytes does not fit the frame mailbox; not attached",
                               len(data))
                data = b""
            self._pickled_telemetry = (latest, data)
        return self._pickled_telemetry[1], heartbeat_age

    def _send(self, child: ChildProcess, message: ToChild) -> bool:
        """Send one message to ``child``; False when it is gone (the end of its pipe reports that)."""
        try:
            with self._send_lock:
                child.conn.send(message)
        except OSError:
            return False
        return True

    def _forget(self, names: list[str]) -> None:
        self._to_forget.extend(names)

    def _release(self, child: ChildProcess, names: list[str]) -> None:
        with self._lock:
            slots = [child.held.pop(name) for name in names if name in child.held]
        for slot in slots:
            self._ring.release_child(slot)

    # -- the child's messages (on the loop, when its pipe is readable) -----------------------------

    def _on_readable(self, child: ChildProcess) -> None:
        """Read the pipe; when the previous read was under :data:`RESULTS_POLL_S` ago, poll it from now on."""
        now = time.monotonic()
        frequent, child.last_read_s = now - child.last_read_s < RESULTS_POLL_S, now
        if self._read(child) is not None and frequent:
            loop = asyncio.get_running_loop()
            loop.remove_reader(child.inbox.fileno())
            loop.call_later(RESULTS_POLL_S, self._poll, child)

    def _poll(self, child: ChildProcess) -> None:
        """Read what came since the last poll; when nothing did, wait for the pipe to be readable again."""
        if child.inbox.closed:
            return
        count = self._read(child)
        if count is None:
            return
        loop = asyncio.get_running_loop()
        if count:
            loop.call_later(RESULTS_POLL_S, self._poll, child)
        else:
            loop.add_reader(child.inbox.fileno(), self._on_readable, child)

    def _read(self, child: ChildProcess) -> int | None:
        """Handle every message that has arrived; how many there were, None when the pipe ended."""
        messages = child.inbox.read()
        if messages is None:
            self._hang_up(child)
            return None
        for data, buffers in messages:
            try:
                message = pickle.loads(data, buffers=buffers)
            except Exception:  # noqa: BLE001 - a value that cannot be unpickled here: say so, go on
                logger.exception("ProcessWorker(%s): unreadable message from pid %s", self.spec, child.pid)
                continue
            if isinstance(message, Result):
                self._take_result(child, message)
            else:
                self._on_message(child, message)
        return len(messages)

    def _hang_up(self, child: ChildProcess) -> None:
        """Stop reading ``child``'s pipe and close our ends of it (the child ended, or is being killed); the
        connection under the send lock, so that a send never writes to a reused descriptor."""
        if child.inbox.closed:
            return
        loop = self._loop
        if loop is not None and not loop.is_closed():
            loop.remove_reader(child.inbox.fileno())
        child.inbox.close()
        with self._send_lock:
            child.conn.close()

    def _ended(self, child: ChildProcess, returncode: int) -> None:
        """``child`` ended (its group killed, it reaped): take what it sent before, stop autonomy at once, report
        once its last output is in."""
        if not child.inbox.closed:
            self._read(child)
        self._hang_up(child)
        self._on_death(child, returncode)
        if self._closing:  # nothing to report: no wait for its output
            self._on_exit(child, returncode)
        else:
            child.exit_report = asyncio.create_task(self._report_exit(child, returncode),
                                                    name=f"processor {child.pid} exit")

    async def _report_exit(self, child: ChildProcess, returncode: int) -> None:
        if child.output_reader is not None:
            await asyncio.get_running_loop().run_in_executor(None, child.output_reader.join, 0.5)
        self._on_exit(child, returncode)

    def _take_result(self, child: ChildProcess, message: Result) -> None:
        with self._lock:
            offered = child.offered.pop(message.gen, None)
            # A copied-in frame's overlay is in the slot: lend it before the child's hold goes.
            slot_view = self._ring.lend(offered.slot) if offered is not None and offered.copied else None
        if offered is not None:
            offered.buffer.mark_read(offered.frame.seq)  # taken (a replay knew at the claim: _wait_claimed)
        self._release(child, message.released)
        if offered is None or child is not self._child or self._closing:
            return
        frame = offered.frame
        if slot_view is not None:
            frame = Frame(slot_view, frame.seq, frame.t_mono_ns, frame.t_wall_ns)
        result = ProcessedFrame(frame=frame, t_start_ns=message.t_start_ns, t_end_ns=message.t_end_ns,
                                t_vector_ns=message.t_vector_ns, vector=message.vector, error=message.error,
                                box=message.box)
        self._store(message.saves, result)
        if result.error:
            self.stats.errors += 1
            self.consecutive_errors += 1
        else:
            self.consecutive_errors = 0
        if self.stage_clock is not None:
            self.stage_clock(result)
        self.stats.add(result.frame.seq, result.frame.t_mono_ns, result.t_start_ns, result.t_end_ns,
                       result.t_vector_ns or result.t_end_ns)
        self.last = result
        self._on_result(result)

    def _store(self, saves: list[Save], result: ProcessedFrame | None) -> None:
        """Replay the child's ``tmMgr.save`` calls here, where the recorder is."""
        if not saves or self.telemetry is None:
            return
        self.current = result
        try:
            for image, extra in saves:
                self.telemetry.save(image, **extra)
        finally:
            self.current = None

    def _on_message(self, child: ChildProcess, message: Ready | LoadError | Reply) -> None:
        if isinstance(message, Ready):
            if not child.ready.done():
                child.ready.set_result(message.info)
        elif isinstance(message, LoadError):
            if not child.ready.done():
                child.ready.set_exception(ProcessorLoadError(message.message, path=message.path,
                                                             class_name=message.class_name, missing=message.missing))
        elif isinstance(message, Reply):
            self._release(child, message.released)
            self._store(message.saves, None)
            call = child.calls.pop(message.call_id, None)
            if call is not None and not call.future.done():
                if message.ok:
                    call.future.set_result(Answer(message.value, message.t_taken_ns))
                else:
                    call.future.set_exception(ProcessorRaised(message.value))

    def _on_death(self, child: ChildProcess, returncode: int) -> None:
        """The current child is gone: stop autonomy at once (``on_fault``), before anything else."""
        if child is self._child and not self._closing:
            self.state_text = "crashed"
            self._on_fault(f"processor (pid {child.pid}) {self._reason(child, returncode)}")

    def _reason(self, child: ChildProcess, returncode: int) -> str:
        return child.kill_reason or describe_exit(returncode, self.memory_mb)

    def _on_exit(self, child: ChildProcess, returncode: int) -> None:
        reason = self._reason(child, returncode)
        with self._lock:
            child.offered.clear()
            child.mailbox.close()
        self._release(child, list(child.held))
        tail = child.last_output()
        if not child.ready.done():
            output = f"; its output:\n{tail}" if tail else ""
            child.ready.set_exception(ProcessorLoadError(
                f"the processor's process {reason} while loading {self.spec}{output}",
                class_name=self.spec.rpartition(":")[2]))
        for call in child.calls.values():
            if not call.future.done():
                call.future.set_exception(UavError(f"{call.what} not answered: the processor {reason}"))
        if child in self._all_children:
            self._all_children.remove(child)
        if child is not self._child or self._closing:
            return
        self._child = None
        message = f"processor (pid {child.pid}) {reason}"
        self.events.emit("error", "processor", message + (f"; last output:\n{tail}" if tail else ""))
        self._restart_task = asyncio.create_task(self._restart(reason), name="processor restart")

    async def _restart(self, reason: str) -> None:
        """Start a fresh child after 1, 2, 4 ... s; give up after MAX_RESTARTS within a minute."""
        while not self._closing:
            now = time.monotonic()
            while self._restarts and self._restarts[0] < now - RESTART_WINDOW_S:
                self._restarts.popleft()
            if len(self._restarts) >= MAX_RESTARTS:
                self.state_text = f"crashed: {reason}"
                self.events.emit("error", "processor", f"gave up: {MAX_RESTARTS} restarts within "
                                 f"{RESTART_WINDOW_S:g} s; the processor stays off ({reason}); fix it and 'reload'")
                return
            attempt = len(self._restarts) + 1
            self.state_text = f"restarting {attempt}"
            await asyncio.sleep(self.first_backoff_s * 2 ** (attempt - 1))
            self._restarts.append(time.monotonic())
            try:
                child = await self._start_child()
            except ProcessorLoadError as exc:
                reason = f"restart failed: {exc}"
                self.events.emit("error", "processor", f"restart {attempt} failed: {exc}")
                continue
            self._adopt(child)
            self.events.emit("warning", "processor", f"processor restarted (pid {child.pid}, attempt {attempt}); "
                             "its state is new: select the target again")
            return

    def _reap(self, timeout: float) -> None:
        """Wait until every child has been reaped and its output read to the end (by its own threads)."""
        deadline = time.monotonic() + timeout
        for child in list(self._all_children):  # the loop removes those it saw end
            if not child.join_threads(max(0.0, deadline - time.monotonic())):
                logger.error("ProcessWorker(%s): pid %s %s", self.spec, child.pid, "still holds its output open: a "
                             "process it started left its group" if child.ended.is_set() else "did not exit")


def _abandon(child: ChildProcess) -> None:
    """Kill a child whose loading nobody waits for any more (timed out, or the start was cancelled: a stop, a quit).

    Its ``ready`` is cancelled, so that its end does not set an exception no one will retrieve (asyncio would log
    "Future exception was never retrieved").
    """
    child.kill("killed")
    if not child.ready.done():
        child.ready.cancel()
    elif not child.ready.cancelled():
        child.ready.exception()  # retrieved: what it says is reported by whoever started it, if anyone


def _call_soon(loop: asyncio.AbstractEventLoop, callback: Callable[..., None], *args: Any) -> None:
    """``callback(*args)`` on ``loop``, from any thread; nothing once the loop is closed."""
    with contextlib.suppress(RuntimeError):
        loop.call_soon_threadsafe(callback, *args)

