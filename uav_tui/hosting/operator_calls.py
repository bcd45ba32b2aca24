"""The operator's calls into the processor (F-keys, target selection): in order, each bounded in time.

A processor answers one call at a time, so a call asked while an earlier one hangs cannot be answered
before it. Each call is therefore sent only once the one before it is settled, and it waits at most
``timeout`` seconds from when it was asked, queueing included. When a call is given up unanswered, the
calls queued behind it are given up at the same moment, never sent; and until the processor returns
from it, a new call is refused at once. No call waits its own full timeout behind a hung one.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Awaitable, Callable

from uav_tui.errors import UavError
from uav_tui.hosting.host import Answer


class _Call:
    def __init__(self, what: str, timeout: float) -> None:
        self.what = what
        self.asked = time.monotonic()
        self.deadline = self.asked + timeout
        self.settled: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        """Done once it was answered, given up or refused: the next call may go."""
        self.answer: asyncio.Future[Answer] | None = None
        """The call in the processor once sent; left running when given up, so its return is known."""

    def hung(self) -> bool:
        """Sent, given up unanswered, and the processor has still not returned from it."""
        return self.settled.done() and self.answer is not None and not self.answer.done()

    def settle(self) -> None:
        if not self.settled.done():
            self.settled.set_result(None)

    def left(self) -> float:
        return max(0.0, self.deadline - time.monotonic())


class ProcessorCalls:
    """The queue of the operator's calls into one core's processor (used on the event loop)."""

    def __init__(self) -> None:
        self._asked: _Call | None = None
        """The newest call asked: the next one goes after it."""
        self._sent: _Call | None = None
        """The newest call sent to the processor."""

    async def call(self, what: str, send: Callable[[], Awaitable[Answer]], timeout: float) -> Answer:
        """``send()`` once the calls asked before it are settled; its answer, within ``timeout`` s of now.

        Args:
            what: the call as the operator reads it (``CsrtTracker.customize_processing(1)``).
            send: starts the call in the processor (the worker's ``call``).
            timeout: ``processor_call_timeout``.

        Raises:
            UavError: not answered in time, or not sent because the processor is still in an earlier call.
            Whatever the call raised (the processor's exception).
        """
        mine = _Call(what, timeout)
        ahead, self._asked = self._asked, mine
        try:
            if ahead is not None and not ahead.settled.done():
                await asyncio.wait({ahead.settled}, timeout=mine.left())
            if (sent := self._sent) is not None and sent.hung():
                raise UavError(f"{what} not sent: the processor has not returned from {sent.what} for "
                               f"{time.monotonic() - sent.asked:.1f} s (processor_call_timeout {timeout:g} s); "
                               "it may be hung")
            if ahead is not None and not ahead.settled.done():
                raise UavError(f"{what} not sent within {timeout:g} s: the processor is still busy with "
                               f"{ahead.what} (processor_call_timeout)")
            self._sent, mine.answer = mine, asyncio.ensure_future(send())
            mine.answer.add_done_callback(_retrieved)  # its error is read, also once it is given up
            done, _ = await asyncio.wait({mine.answer}, timeout=mine.left())
            if not done:
                raise UavError(f"{what} did not return within {timeout:g} s (processor_call_timeout); the "
                               "processor may be hung")
            return mine.answer.result()
        finally:
            mine.settle()


def _retrieved(answer: asyncio.Future[Answer]) -> None:
    if not answer.cancelled():
        answer.exception()
