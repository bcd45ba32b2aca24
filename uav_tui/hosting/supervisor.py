"""Watchdog and restarts for the process host's children.

The watchdog (:meth:`ChildSupervisor.watch`, on the loop) kills a child that stays silent longer than
``processor_timeout``; a child that dies for any reason is reported (exit code or signal, last lines of its
output), ``on_fault`` stops autonomy, and a fresh child with the same arguments is started after 1, 2, 4 ... s,
at most :data:`MAX_RESTARTS` times a minute. Whenever a child is killed or ends, so do the processes it started
(its process group).
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import functools
import logging
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from processors import LoadedProcessor
from processors.base import ProcessorInfo
from processors.errors import ProcessorLoadError
from processors.frame_telemetry import DEFAULT_SAVE_MAX_HZ
from uav_tui.errors import UavError
from uav_tui.events import EventLog
from uav_tui.hosting.child_link import ChildLink
from uav_tui.hosting.child_process import ChildProcess, describe_exit, say_output, spawn
from uav_tui.hosting.frame_feeder import FrameFeeder
from uav_tui.hosting.host import HostPhase, HostState
from uav_tui.hosting.wire import Load
from uav_tui.output.line_budget import LineBudget

logger = logging.getLogger(__name__)

WATCH_PERIOD_S = 0.05
LOAD_TIMEOUT_S = 60.0
"""A processor that takes longer to import and construct is killed (YOLO on a Pi needs a few seconds)."""
MAX_RESTARTS = 5
"""Restarts allowed within :data:`RESTART_WINDOW_S`; one more crash and the platform gives up."""
RESTART_WINDOW_S = 60.0
SHORT_OF_ROOM = frozenset({errno.EMFILE, errno.ENFILE, errno.EAGAIN, errno.ENOMEM, errno.ENOSPC})
"""Why a process cannot start for now (the system is out of descriptors, processes or memory): tried again, not
counted as a restart. Any other OSError (a moved interpreter, no permission) counts like a failed load."""


class ChildSupervisor:
    """Starts the children, watches them, reports their ends and restarts the processor.

    The current child is the one :class:`~uav_tui.hosting.frame_feeder.FrameFeeder` feeds (``feeder.child``).
    Arguments as :class:`~uav_tui.hosting.process_host.SubprocessHost`'s.
    """

    def __init__(self, spec: str, kwargs: dict[str, Any], *, link: ChildLink, feeder: FrameFeeder, events: EventLog,
                 on_fault: Callable[[str], None], timeout_s: float, memory_mb: float | None, save_images: bool,
                 save_max_hz: float = DEFAULT_SAVE_MAX_HZ, first_backoff_s: float = 1.0) -> None:
        self.spec, self.kwargs = spec, kwargs
        self.processor = LoadedProcessor(instance=None, info=ProcessorInfo(spec, None, frozenset()), spec=spec,
                                         kwargs=kwargs)
        """What was loaded; ``instance`` is None: the object lives in the child."""
        self.events = events
        self.timeout_s = timeout_s
        self.memory_mb = memory_mb
        self.save_images = save_images
        self.save_max_hz = save_max_hz
        self.first_backoff_s = first_backoff_s
        self.next_track_id = 0
        """Above every ``track_id`` seen: where a new child's tracks are numbered from."""
        self.phase = HostPhase(HostState.STARTING)
        self.children: list[ChildProcess] = []
        """Every child not yet seen to end (the current one, those being replaced or killed)."""
        self._link = link
        self._feeder = feeder
        self._on_fault = on_fault
        self._restarts: deque[float] = deque()
        self._restart_task: asyncio.Task[None] | None = None
        self._closing = False
        # Children are started from this one long-lived thread: the child's parent-death signal
        # (PR_SET_PDEATHSIG) fires when the *thread* that started it ends, not only the process.
        self._spawner = ThreadPoolExecutor(1, thread_name_prefix="processor-spawner")
        self._output: LineBudget[bytes] = LineBudget(say_output, self._say_left_out)
        """What the processor prints or logs (any of its children): a burst, then a line a second, and a count."""

    @property
    def child(self) -> ChildProcess | None:
        """The current child."""
        return self._feeder.child

    def running_child(self) -> ChildProcess:
        """The current child; UavError when there is none running."""
        child = self.child
        if child is None or child.ended.is_set():
            raise UavError(f"the processor is not running ({self.phase})")
        return child

    async def start_child(self) -> ChildProcess:
        """A new child with the processor loaded in it (ProcessorLoadError when it cannot be, or takes too long)."""
        loop = asyncio.get_running_loop()
        spawning = loop.run_in_executor(self._spawner, spawn, loop.create_future(), self._output.lines)
        try:
            child = await asyncio.shield(spawning)
        except asyncio.CancelledError:  # the spawn goes on in its thread: wait for it, then undo what it started
            await _discard(spawning)
            raise
        self.children.append(child)
        child.watch_exit(functools.partial(_call_soon, loop, self._ended, child))
        self._link.listen(child)
        self._link.send(child, Load(self.spec, self.kwargs, self.memory_mb, self.save_images, self.save_max_hz,
                                    self.next_track_id))
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

    def adopt(self, child: ChildProcess) -> None:
        """Make ``child`` (loaded) the current one: it gets the frames from now on."""
        self.processor = LoadedProcessor(instance=None, info=child.ready.result(), spec=self.spec, kwargs=self.kwargs)
        self._feeder.feed(child)
        self.phase = HostPhase(HostState.RUNNING)

    async def replace(self) -> ProcessorInfo:
        """Start a new child with the code as it is now; swap only once it loaded (else the old one keeps running)."""
        fresh = await self.start_child()
        if self._restart_task is not None:  # the operator's fixed code replaces a crashed processor's restarts
            self._restart_task.cancel()
            self._restarts.clear()
        old = self.child
        self.adopt(fresh)
        if old is not None:
            self._retire(old, "replaced by a reload")
        return fresh.ready.result()

    async def watch(self) -> None:
        """Kill a child silent for longer than ``timeout_s``; until cancelled."""
        while True:
            await asyncio.sleep(WATCH_PERIOD_S)
            child = self.child
            since = child.busy_since_ns() if child is not None else None
            busy = (time.monotonic_ns() - since) / 1e9 if since else 0.0
            if child is not None and busy > self.timeout_s and not child.kill_reason:
                child.kill(f"no answer for {busy:.1f} s (processor_timeout = {self.timeout_s:g} s): killed")

    def close(self) -> None:
        """Kill every child at once (whatever the processor is doing) and start no other. Idempotent."""
        self._closing = True
        if self._restart_task is not None:
            self._restart_task.cancel()
        for child in self.children:
            child.kill("stopped")  # reaped by its exit watch's thread, not the loop's executor (a failed start ends it)
            self._link.hang_up(child)
            for call in child.calls.values():
                if not call.future.done():
                    call.future.cancel()
        self._spawner.shutdown(wait=False)
        self._output.close()

    def reap(self, timeout: float) -> None:
        """Wait until every child has been reaped and its output read to the end (by its own threads)."""
        deadline = time.monotonic() + timeout
        for child in list(self.children):  # the loop removes those it saw end
            if not child.join_threads(max(0.0, deadline - time.monotonic())):
                logger.error("SubprocessHost(%s): pid %s %s", self.spec, child.pid, "still holds its output open: a "
                             "process it started left its group" if child.ended.is_set() else "did not exit")

    def _say_left_out(self, count: int) -> None:
        self.events.emit("warning", "processor", f"{count} more lines of the processor's output left out (too many at "
                         "once; the crash report has the last ones)")

    def _retire(self, child: ChildProcess, why: str) -> None:
        child.kill(why)
        for call in child.calls.values():
            if not call.future.done():
                call.future.set_exception(UavError(f"{call.what} not answered: the processor was {why}"))

    # -- a child's end (on the loop) ---------------------------------------------------------------

    def _ended(self, child: ChildProcess, returncode: int) -> None:
        """``child`` ended (its group killed, it reaped): take what it sent before, stop autonomy at once, report
        once its last output is in."""
        if not child.inbox.closed:
            self._link.read(child)
        self._link.hang_up(child)
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

    def _on_death(self, child: ChildProcess, returncode: int) -> None:
        """The current child is gone: stop autonomy at once (``on_fault``), before anything else."""
        if child is self.child and not self._closing:
            self.phase = HostPhase(HostState.CRASHED)
            self._on_fault(f"processor (pid {child.pid}) {self._reason(child, returncode)}")

    def _reason(self, child: ChildProcess, returncode: int) -> str:
        return child.kill_reason or describe_exit(returncode, self.memory_mb)

    def _on_exit(self, child: ChildProcess, returncode: int) -> None:
        reason = self._reason(child, returncode)
        self._feeder.retire(child)
        tail = child.last_output()
        if not child.ready.done():
            output = f"; its output:\n{tail}" if tail else ""
            child.ready.set_exception(ProcessorLoadError(
                f"the processor's process {reason} while loading {self.spec}{output}",
                class_name=self.spec.rpartition(":")[2]))
        for call in child.calls.values():
            if not call.future.done():
                call.future.set_exception(UavError(f"{call.what} not answered: the processor {reason}"))
        if child in self.children:
            self.children.remove(child)
        if child is not self.child or self._closing:
            return
        self._feeder.feed(None)
        message = f"processor (pid {child.pid}) {reason}"
        self.events.emit("error", "processor", message + (f"; last output:\n{tail}" if tail else ""))
        self._restart_task = asyncio.create_task(self._restart(reason), name="processor restart")

    async def _restart(self, reason: str) -> None:
        """Start a fresh child after 1, 2, 4 ... s; give up after MAX_RESTARTS within a minute.

        A start the system refuses (``OSError``: no descriptors or processes left) is said once and tried again
        after the same wait, without counting as a restart: the processor did nothing wrong.
        """
        short_of = False
        while not self._closing:
            now = time.monotonic()
            while self._restarts and self._restarts[0] < now - RESTART_WINDOW_S:
                self._restarts.popleft()
            if len(self._restarts) >= MAX_RESTARTS:
                self.phase = HostPhase(HostState.CRASHED, reason=reason)
                self.events.emit("error", "processor", f"gave up: {MAX_RESTARTS} restarts within "
                                 f"{RESTART_WINDOW_S:g} s; the processor stays off ({reason}); fix it and 'reload'")
                return
            attempt = len(self._restarts) + 1
            self.phase = HostPhase(HostState.RESTARTING, attempt)
            await asyncio.sleep(self.first_backoff_s * 2 ** (attempt - 1))
            self._restarts.append(time.monotonic())
            try:
                child = await self.start_child()
            except ProcessorLoadError as exc:
                reason = f"restart failed: {exc}"
                self.events.emit("error", "processor", f"restart {attempt} failed: {exc}")
                continue
            except OSError as exc:
                if exc.errno not in SHORT_OF_ROOM:  # a moved interpreter, no permission: counted like a failure
                    reason = f"restart failed: {exc}"
                    self.events.emit("error", "processor", f"restart {attempt} failed: {exc}")
                    continue
                # the system's limit (descriptors, processes, memory), not the processor's fault
                self._restarts.pop()  # not counted: the same attempt again after its wait, until the system has room
                if not short_of:
                    self.events.emit("error", "processor", f"restart {attempt} could not start a process "
                                     f"({exc.strerror or exc}); trying again until the system has room")
                short_of = True
                continue
            self.adopt(child)
            self.events.emit("warning", "processor", f"processor restarted (pid {child.pid}, attempt {attempt}); "
                             "its state is new: select the target again")
            return


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


async def _discard(spawning: asyncio.Future[ChildProcess]) -> None:
    """The child of a start that was cancelled while it spawned: killed, reaped, its pipe and mailbox closed (no
    shared memory left behind), before the cancellation goes on."""
    try:
        child = await spawning
    except Exception:  # noqa: BLE001 - the spawn failed: nothing was started
        return
    child.kill("the start was cancelled")
    child.inbox.close()
    child.conn.close()
    child.mailbox.close()
    await asyncio.to_thread(child.proc.wait)


def _call_soon(loop: asyncio.AbstractEventLoop, callback: Callable[..., None], *args: Any) -> None:
    """``callback(*args)`` on ``loop``, from any thread; nothing once the loop is closed."""
    with contextlib.suppress(RuntimeError):
        loop.call_soon_threadsafe(callback, *args)
