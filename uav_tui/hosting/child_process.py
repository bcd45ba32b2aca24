"""One processor process as the platform sees it: how it is started, what it printed, how it ended.

:class:`ChildProcess` is the handle :class:`~uav_tui.hosting.process_host.SubprocessHost` keeps per child:
the process, its pipe and frame mailbox, the frames and calls it has been offered, the slots it may still reference, and
the last lines of its output (stdout and stderr together, forwarded escaped to the platform's stdout
the way ``print()`` reaches it with thread isolation, and kept for the crash report). Its log records
are logged by the platform, through the platform's own (escaping) handlers.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import multiprocessing
import os
import signal
import subprocess
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from multiprocessing.connection import Connection
from typing import Any

from processors.base import ProcessorInfo
from sources.buffer import Frame, FrameBuffer
from uav_tui.hosting import malloc_tuning, opencv_pool
from uav_tui.hosting.child import LOG_LEVEL_ENV, MEMORY_EXIT_CODE, parse_log_line
from uav_tui.hosting.frame_mailbox import FrameMailbox
from uav_tui.hosting.frame_ring import Slot, ensure_resource_tracker, job_signals_blocked
from uav_tui.hosting.pipe import Inbox
from uav_tui.output.text import safe, shorten

TAIL_LINES = 30
"""Lines of the child's output kept for the crash report (a faulthandler dump fits)."""
LINE_CHARS = 300
"""A longer line of output is cut (on the terminal and in the crash report)."""
READ_BYTES = 64 * 1024
"""The child's output is read in chunks this big: a flood costs the platform little, and the child never waits."""
MAX_LINE_BYTES = 64 * 1024
"""A line still unfinished after this many bytes is taken as it is: memory stays bounded whatever is printed."""


@dataclass(slots=True)
class Offered:
    """A frame put in the child's mailbox, until it is replaced untaken or its result is back."""

    buffer: FrameBuffer
    frame: Frame
    slot: Slot
    copied: bool
    """The frame was copied into ``slot`` (False: it was captured there)."""


@dataclass(slots=True)
class PendingCall:
    """An operator call sent to the child and not answered yet."""

    what: str
    sent_ns: int
    future: asyncio.Future[Any]


@dataclass(eq=False)
class ChildProcess:
    """One processor process, its pipe and what it has been given."""

    proc: subprocess.Popen[bytes]
    conn: Connection
    mailbox: FrameMailbox
    ready: asyncio.Future[ProcessorInfo]
    tail: deque[bytes] = field(default_factory=lambda: deque(maxlen=TAIL_LINES))
    """The last lines of its output as read, cut to a few times :data:`LINE_CHARS` (see :meth:`last_output`)."""
    offered: dict[int, Offered] = field(default_factory=dict)
    """By offer gen: the frame on offer, and those the child claimed whose result is not back."""
    last_claim: tuple[int, int] = (0, 0)
    """(gen, monotonic ns) of the child's newest claim, as last read from its mailbox."""
    calls: dict[int, PendingCall] = field(default_factory=dict)
    held: dict[str, Slot] = field(default_factory=dict)
    """Slots the child may still reference."""
    kill_reason: str = ""
    """Why the platform killed it (empty: it died by itself)."""
    output_reader: threading.Thread | None = None
    """Reads its output (stdout and stderr) until every process that holds it ended."""
    inbox: Inbox = field(init=False)
    ended: threading.Event = field(default_factory=threading.Event)
    """Set once it ended and was reaped (by :meth:`watch_exit`'s thread, the only one that reaps it)."""
    exit_watcher: threading.Thread | None = None
    """The thread of :meth:`watch_exit`."""
    exit_report: asyncio.Task[None] | None = None
    """Reports its end once its last output is in."""
    last_read_s: float = 0.0
    """When (monotonic s) its pipe was last found readable."""
    unreadable: int = 0
    """Messages from it that did not decode (a hostile or broken child): counted, a few said."""

    def __post_init__(self) -> None:
        self.inbox = Inbox(self.conn)

    @property
    def pid(self) -> int:
        return self.proc.pid

    def last_output(self) -> str:
        """The last lines it printed (log records left out), escaped, each cut to :data:`LINE_CHARS`."""
        lines = (raw.decode("utf-8", "replace").rstrip("\r") for raw in self.tail)
        return "\n".join(shorten(safe(line), LINE_CHARS) for line in lines if parse_log_line(line) is None)

    def busy_since_ns(self) -> int | None:
        """When the oldest frame or call still unanswered was sent (None when idle)."""
        starts = [c.sent_ns for c in self.calls.values()]
        self.last_claim = self.mailbox.last_claim() or self.last_claim
        gen, claimed_ns = self.last_claim
        if gen in self.offered:  # claimed, its result not back yet
            starts.append(claimed_ns)
        return min(starts, default=None)

    def kill(self, reason: str) -> None:
        """SIGKILL, whatever the processor is doing, with what it started (:meth:`kill_group`); ``reason`` goes
        into the report."""
        self.kill_reason = self.kill_reason or reason
        self.kill_group()

    def kill_group(self) -> None:
        """SIGKILL every process of its process group: it and the processes it started (``subprocess``,
        ``multiprocessing``), unless one left the group. Only until it is reaped: till then the group's id, its
        pid, cannot name another process's group."""
        if self.proc.returncode is None:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(self.proc.pid, signal.SIGKILL)

    def watch_exit(self, on_end: Callable[[int], None]) -> None:
        """From now on, wait on a thread of its own for it to end, however it ends; then kill what it left running
        in its group, reap it and call ``on_end(exit status)`` on that thread.

        Its end is known from the process itself, not from its pipe: a process it forked (``multiprocessing``'s
        default on Linux) holds the pipe open after it died.
        """
        self.exit_watcher = threading.Thread(target=self._wait_exit, args=(on_end,), name=f"processor-{self.pid}-exit",
                                             daemon=True)
        self.exit_watcher.start()

    def join_threads(self, timeout: float) -> bool:
        """Wait up to ``timeout`` s for its exit watch and its output reader to finish; True once both have."""
        deadline = time.monotonic() + timeout
        for thread in (self.exit_watcher, self.output_reader):
            if thread is not None:
                thread.join(max(0.0, deadline - time.monotonic()))
        return not any(thread is not None and thread.is_alive() for thread in (self.exit_watcher, self.output_reader))

    def _wait_exit(self, on_end: Callable[[int], None]) -> None:
        with contextlib.suppress(ChildProcessError):
            os.waitid(os.P_PID, self.proc.pid, os.WEXITED | os.WNOWAIT)  # ended, not reaped: the group id is ours
        self.kill_group()
        returncode = self.proc.wait()
        self.ended.set()
        on_end(returncode)


def spawn(ready: asyncio.Future[ProcessorInfo], output: Callable[[list[bytes]], None]) -> ChildProcess:
    """Start ``python -m uav_tui.hosting.child`` with a pipe and a frame mailbox; its output is read on a thread and its
    lines given to ``output`` (a :class:`~uav_tui.output.line_budget.LineBudget`'s ``lines``: see :func:`say_output`).

    The child has a process group of its own: a terminal's Ctrl-C, Ctrl-Z and hang-up (sent to every process of
    the job) reach only the platform, which decides what happens to the processor. Not a session of its own: the
    kernel's autogroup scheduling would then share the CPU between the two sessions, not their threads, and
    the hand-off cost more CPU (measured, position hold at 640x480).
    """
    ours, theirs = multiprocessing.Pipe()
    try:
        ensure_resource_tracker()
        mailbox = FrameMailbox.create()
    except BaseException:  # out of descriptors or shared memory: nothing left open
        ours.close()
        theirs.close()
        raise
    env = {**opencv_pool.child_environment(malloc_tuning.child_environment(os.environ)),
           "PYTHONPATH": os.pathsep.join(p for p in sys.path if p),  # its imports
           LOG_LEVEL_ENV: logging.getLevelName(logging.getLogger().getEffectiveLevel())}
    try:
        with job_signals_blocked():  # the child unblocks them once it is itself
            proc = subprocess.Popen([sys.executable, "-m", "uav_tui.hosting.child", str(theirs.fileno()),
                                     mailbox.address],
                                    pass_fds=(theirs.fileno(), *mailbox.fds), stdin=subprocess.DEVNULL,
                                    stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env,
                                    process_group=0)
    except BaseException:
        mailbox.close()
        ours.close()
        raise
    finally:
        theirs.close()
    child = ChildProcess(proc, ours, mailbox, ready)
    child.output_reader = threading.Thread(target=_read_output, args=(child, output),
                                           name=f"processor-{proc.pid}-output",
                                           daemon=True)
    child.output_reader.start()
    return child


def _read_output(child: ChildProcess, output: Callable[[list[bytes]], None]) -> None:
    """Read the child's output (stdout and stderr) in big chunks until every process holding it ended; give its lines
    to ``output`` and keep the last ones in ``child.tail``. Lines are never decoded here: a flood of them costs
    a split and a count."""
    assert child.proc.stdout is not None
    with child.proc.stdout as pipe:
        partial = b""
        while chunk := _read(pipe.fileno()):
            *lines, partial = (partial + chunk).split(b"\n")
            if len(partial) >= MAX_LINE_BYTES:  # a line that does not end is taken in pieces
                lines.append(partial)
                partial = b""
            if lines:
                child.tail.extend(line[:4 * LINE_CHARS] for line in lines[-TAIL_LINES:])
                output(lines)
        if partial:
            child.tail.append(partial[:4 * LINE_CHARS])
            output([partial])


def _read(fd: int) -> bytes:
    """What the pipe has (waits for something); empty at its end."""
    try:
        return os.read(fd, READ_BYTES)
    except OSError:
        return b""


def say_output(raw: bytes) -> None:
    """One line of the child's output, as the platform says it: a log record is logged here (through the platform's
    escaping handlers), anything else is printed on stdout escaped and cut, as ``print()`` would with thread
    isolation. Called on the output reader's thread, within the worker's line budget."""
    line = raw.decode("utf-8", "replace").rstrip("\r")
    if record := parse_log_line(line):
        level, name, text = record
        logging.getLogger(name).log(level, "%s", shorten(text, 4000))
        return
    with contextlib.suppress(OSError, ValueError):  # one write: a line is dropped whole, or kept
        sys.stdout.write(shorten(safe(line), LINE_CHARS) + "\n")
        sys.stdout.flush()


def describe_exit(returncode: int, memory_mb: float | None) -> str:
    """``exited with code 3``, ``killed by SIGSEGV``, ``ran out of memory: processor_memory_mb = 300 MB reached``."""
    if returncode == MEMORY_EXIT_CODE and memory_mb:
        return f"ran out of memory: processor_memory_mb = {memory_mb:g} MB reached"
    if returncode < 0:
        name = signal.Signals(-returncode).name if -returncode in signal.valid_signals() else str(-returncode)
        hint = " (out of memory? the kernel's OOM killer sends it)" if -returncode == signal.SIGKILL else ""
        return f"killed by {name}{hint}"
    return f"exited with code {returncode}"


def rss_mb(pid: int) -> float | None:
    """Resident memory of ``pid`` in MB (Linux ``/proc``), None where unknown."""
    try:
        with open(f"/proc/{pid}/statm") as statm:
            return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6
    except (OSError, ValueError, IndexError):
        return None
