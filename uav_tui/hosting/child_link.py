"""The process host's link to its children: messages sent down their pipes, and theirs read on the event loop.

A child's messages (:mod:`uav_tui.hosting.wire`) are read by the event loop itself whenever its pipe is readable
(:class:`~uav_tui.hosting.pipe.Inbox`), never blocking it; when they come faster than :data:`RESULTS_POLL_S` they
are polled in batches instead. Each is decoded and checked (:mod:`uav_tui.hosting.codec`): a result or reply that
does not fit the schema is that frame's (or call's) error; any other message that does not is logged and dropped.
"""

from __future__ import annotations

import asyncio
import itertools
import logging
import threading
import time
from typing import Any, Protocol

from processors.errors import ProcessorLoadError
from uav_tui.hosting.child_process import ChildProcess, PendingCall
from uav_tui.hosting.codec import UnreadableResult, WireError, decode_from_child
from uav_tui.hosting.host import Answer
from uav_tui.hosting.pipe import PipeCorrupt, send_to_child
from uav_tui.hosting.wire import Call, FromChild, LoadError, Ready, Reply, ReplyHead, Result, Save, ToChild

logger = logging.getLogger(__name__)

RESULTS_POLL_S = 0.001
"""The child's messages that come closer together than this (a replay's results, never a camera's) are read this
often, in batches, instead of each waking the event loop: the child's write then wakes nobody. Messages further
apart are read as they arrive. A result frees its frame's slot, so a poll period passes at most ``MAX_SLOTS`` frames.
(Template matching on a generated 640x480 replay: CPU a frame 1.13x -> 1.09x the bare loop.)"""


class ProcessorRaised(Exception):
    """The researcher's method raised in the child; the message is ``Type: message``."""


class TakesResults(Protocol):
    """Where :class:`ChildLink` hands what a child sent, on the loop: the
    :class:`~uav_tui.hosting.process_host.SubprocessHost`."""

    def take_result(self, child: ChildProcess, message: Result) -> None:
        """A frame's :class:`~uav_tui.hosting.wire.Result`."""

    def take_unreadable(self, child: ChildProcess, unreadable: UnreadableResult) -> None:
        """A result that did not decode: what could be read of it, and why."""

    def take_spent(self, child: ChildProcess, saves: tuple[Save, ...], released: tuple[str, ...]) -> None:
        """A reply's ``tmMgr.save`` calls and the slots it released."""


class ChildLink:
    """Sends to the children and reads what they send, on the event loop.

    Args:
        spec: the processor, for log lines.
        host: where results, unreadable results and replies' saves go (on the loop).
    """

    def __init__(self, spec: str, host: TakesResults) -> None:
        self.spec = spec
        self._host = host
        self._send_lock = threading.Lock()
        self._call_ids = itertools.count(1)
        self._loop: asyncio.AbstractEventLoop | None = None

    def listen(self, child: ChildProcess) -> None:
        """Read ``child``'s messages from now on (on the running loop)."""
        self._loop = asyncio.get_running_loop()
        self._loop.add_reader(child.inbox.fileno(), self._on_readable, child)

    def send(self, child: ChildProcess, message: ToChild) -> bool:
        """Send one message to ``child``; False when it is gone (the end of its pipe reports that)."""
        try:
            with self._send_lock:
                send_to_child(child.conn, message)
        except OSError:
            return False
        return True

    def call(self, child: ChildProcess, method: str, args: tuple[Any, ...]) -> asyncio.Future[Answer] | None:
        """Send a call to ``child``; the future of its answer (ProcessorRaised if it raised), None if it is gone."""
        call_id = next(self._call_ids)
        future: asyncio.Future[Answer] = asyncio.get_running_loop().create_future()
        child.calls[call_id] = PendingCall(f"{method}{args!r}", time.monotonic_ns(), future)
        if not self.send(child, Call(call_id, method, args)):
            child.calls.pop(call_id)
            return None
        return future

    def hang_up(self, child: ChildProcess) -> None:
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

    def read(self, child: ChildProcess) -> int | None:
        """Handle every message that has arrived; how many there were, None when the pipe ended."""
        try:
            messages = child.inbox.read()
        except PipeCorrupt as exc:
            logger.warning("SubprocessHost(%s): pid %s wrote what is no message (%s): its pipe is closed and it is "
                           "restarted", self.spec, child.pid, exc)
            messages = None
        if messages is None:
            self.hang_up(child)
            return None
        for data, buffers in messages:
            try:
                message = decode_from_child(data, buffers)
            except UnreadableResult as exc:
                self._unreadable(child, exc)
                continue
            except WireError as exc:
                child.unreadable += 1
                if child.unreadable in (1, 10, 100, 1000) or child.unreadable % 10_000 == 0:
                    logger.warning("SubprocessHost(%s): %d messages from pid %s were not messages, the last: %s",
                                   self.spec, child.unreadable, child.pid, exc)
                continue
            if isinstance(message, Result):
                self._host.take_result(child, message)
            else:
                self._on_message(child, message)
        return len(messages)

    def _on_readable(self, child: ChildProcess) -> None:
        """Read the pipe; when the previous read was under :data:`RESULTS_POLL_S` ago, poll it from now on."""
        now = time.monotonic()
        frequent, child.last_read_s = now - child.last_read_s < RESULTS_POLL_S, now
        if self.read(child) is not None and frequent:
            loop = asyncio.get_running_loop()
            loop.remove_reader(child.inbox.fileno())
            loop.call_later(RESULTS_POLL_S, self._poll, child)

    def _poll(self, child: ChildProcess) -> None:
        """Read what came since the last poll; when nothing did, wait for the pipe to be readable again."""
        if child.inbox.closed:
            return
        count = self.read(child)
        if count is None:
            return
        loop = asyncio.get_running_loop()
        if count:
            loop.call_later(RESULTS_POLL_S, self._poll, child)
        else:
            loop.add_reader(child.inbox.fileno(), self._on_readable, child)

    def _unreadable(self, child: ChildProcess, exc: UnreadableResult) -> None:
        """A result or reply whose rest did not decode: the frame's error, or the call's."""
        if not isinstance(exc.head, ReplyHead):
            self._host.take_unreadable(child, exc)
            return
        self._host.take_spent(child, (), exc.head.released)
        call = child.calls.pop(exc.head.call_id, None)
        if call is not None and not call.future.done():
            call.future.set_exception(ProcessorRaised(f"WireError: the answer is not data: {exc.reason}"))

    def _on_message(self, child: ChildProcess, message: FromChild) -> None:
        if isinstance(message, Ready):
            if not child.ready.done():
                child.ready.set_result(message.info)
        elif isinstance(message, LoadError):
            if not child.ready.done():
                child.ready.set_exception(ProcessorLoadError(message.message, path=message.path,
                                                             class_name=message.class_name, missing=message.missing))
        elif isinstance(message, Reply):
            self._host.take_spent(child, message.saves, message.released)
            call = child.calls.pop(message.call_id, None)
            if call is not None and not call.future.done():
                if message.ok:
                    call.future.set_result(Answer(message.value, message.t_taken_ns))
                else:
                    call.future.set_exception(ProcessorRaised(message.value))
