"""Every MAVSDK call bounded in time, in a thread that can be abandoned.

MAVSDK 4's asyncio binding runs each blocking call with ``loop.run_in_executor(None, ...)``, and a
call can block forever once the link is gone (a thread stuck in ``Action.hold()`` was seen). In the
loop's standard executor such a thread is joined when ``asyncio.run()`` ends and again when the
interpreter exits, so the process could never exit and kept the serial port. Here:

- :func:`use_abandoning_executor` gives the running loop an :class:`AbandoningExecutor`: one daemon
  thread per call, and a shutdown that does not wait for calls still blocked;
- :func:`bounded` is the one wrapper every MAVSDK call goes through: a timeout, MAVSDK's errors
  translated to ours, and a log line for each call it abandons;
- :class:`Command` is a controller's :func:`bounded` call, as the parts it hands it to see it;
- :class:`Subscriptions` reads MAVSDK's subscriptions in tasks that unsubscribe when they end, and that a
  failing item does not end;
- :func:`release` destroys MAVSDK at close, unless a call is still inside it: then it is let go.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
import weakref
from collections.abc import AsyncGenerator, Awaitable, Callable
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, Protocol, TypeVar

from controllers.errors import FailureKinds
from controllers.mavsdk.errors import map_mavsdk_errors

logger = logging.getLogger(__name__)

T = TypeVar("T")

class AbandoningExecutor(ThreadPoolExecutor):
    """Runs each call in its own daemon thread; :meth:`shutdown` never waits for them.

    A ``ThreadPoolExecutor`` by type only (``loop.set_default_executor`` accepts nothing else); its
    pool is never used. :attr:`running` names the calls still in progress.
    """

    def __init__(self) -> None:
        super().__init__(max_workers=1, thread_name_prefix="mavsdk-unused")
        self._running: dict[int, str] = {}
        self._running_lock = threading.Lock()
        self._shut_down = False

    @property
    def running(self) -> list[str]:
        """Names of the calls whose threads have not returned yet."""
        with self._running_lock:
            return sorted(self._running.values())

    def submit(self, fn: Callable[..., T], /, *args: Any, **kwargs: Any) -> Future[T]:
        future: Future[T] = Future()
        name = getattr(fn, "__qualname__", repr(fn))

        def run() -> None:
            if not future.set_running_or_notify_cancel():
                return
            key = threading.get_ident()
            with self._running_lock:
                self._running[key] = name
            error: BaseException | None = None
            try:
                result = fn(*args, **kwargs)
            except BaseException as exc:  # noqa: BLE001 - handed to the awaiting side
                error = exc
            finally:
                # Off the list before the caller wakes: it may ask what is still running at once.
                with self._running_lock:
                    self._running.pop(key, None)
            if error is None:
                future.set_result(result)
            else:
                future.set_exception(error)

        threading.Thread(target=run, name=f"mavsdk-call-{name}", daemon=True).start()
        return future

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """Return at once: a call blocked in MAVSDK is abandoned (its daemon thread dies with the process)."""
        if self.running and not self._shut_down:
            logger.warning("abandoning calls on the event loop's executor still blocked: %s", ", ".join(self.running))
        self._shut_down = True


_installed: weakref.WeakKeyDictionary[asyncio.AbstractEventLoop, AbandoningExecutor] = weakref.WeakKeyDictionary()


def use_abandoning_executor() -> AbandoningExecutor:
    """Make the running loop's default executor an :class:`AbandoningExecutor` (once per loop)."""
    loop = asyncio.get_running_loop()
    executor = _installed.get(loop)
    if executor is None:
        executor = _installed[loop] = AbandoningExecutor()
        loop.set_default_executor(executor)
    return executor


async def bounded(
    name: str, call: Callable[[], Awaitable[T]], timeout_s: float, heartbeat_age_s: Callable[[], float] | None = None
) -> T:
    """Await one MAVSDK call for at most ``timeout_s``; its errors become ControllerErrors.

    On timeout the call is abandoned (its thread may stay blocked in MAVSDK; it keeps nothing alive)
    and :class:`controllers.errors.LinkLost` or ``CommandDenied(TIMEOUT)`` is raised.
    """
    with map_mavsdk_errors(name, heartbeat_age_s):
        try:
            async with asyncio.timeout(timeout_s):
                return await call()
        except TimeoutError:
            logger.warning("MAVSDK call %s: no answer within %.1f s; abandoned", name, timeout_s)
            raise


class Command(Protocol):
    """A controller's way to make one MAVSDK call: :func:`bounded`, with its timeout and link, after its own checks
    (connected, not closed)."""

    async def __call__(self, name: str, call: Callable[[], Awaitable[T]]) -> T: ...


class Subscriptions:
    """The tasks that read MAVSDK subscriptions; :meth:`close` ends them, each unsubscribed, before MAVSDK goes.

    A cancelled ``async for`` leaves its generator open; Python closes it later, from the garbage collector,
    and a MAVSDK subscription's unsubscribe then ran while MAVSDK was being destroyed in another thread:
    the process died of a segfault (seen once in CI). Each reader here closes its subscription as it ends.
    """

    def __init__(self) -> None:
        self._readers: set[asyncio.Task[None]] = set()

    def read(self, stream: AsyncGenerator[T, None], on_item: Callable[[T], None], name: str) -> asyncio.Task[None]:
        """Call ``on_item`` with each item of ``stream`` (a ``subscribe_*()`` call) in a task of its own.

        An item ``on_item`` raises on costs that item alone: the first failure of each kind (exception type and
        the line that raised it) is logged with its traceback, and the subscription goes on.
        """

        async def run() -> None:
            kinds = FailureKinds()
            try:
                async with contextlib.aclosing(stream):
                    async for item in stream:
                        _call_item(on_item, item, kinds, name)
            except Exception:
                logger.exception("MAVSDK subscription %s failed", name)

        reader = asyncio.create_task(run(), name=name)
        self._readers.add(reader)
        reader.add_done_callback(self._readers.discard)
        return reader

    async def close(self) -> None:
        """End every reader and wait until each has unsubscribed."""
        readers = list(self._readers)
        for reader in readers:
            reader.cancel()
        await asyncio.gather(*readers, return_exceptions=True)


def _call_item(on_item: Callable[[T], None], item: T, kinds: FailureKinds, name: str) -> None:
    """``on_item(item)``; a failure costs that item alone, its kind's first is logged."""
    try:
        on_item(item)
    except Exception as exc:  # noqa: BLE001 - a bug costs one message, not the subscription
        if kind := kinds.first(exc):
            logger.exception("MAVSDK subscription %s: an item failed (%s); the subscription goes on (this failure is "
                             "not logged again)", name, kind)


_abandoned: list[Any] = []
"""MAVSDK instances let go of with calls still blocked in them: kept referenced, never destroyed."""


async def release(mavsdk: Any, executor: AbandoningExecutor, timeout_s: float) -> None:
    """Destroy a MAVSDK instance within ``timeout_s``, or abandon it to the process exit.

    It is never destroyed while a call is still inside it (that can crash the process).
    """
    with contextlib.suppress(TimeoutError):
        async with asyncio.timeout(timeout_s):
            while executor.running:
                await asyncio.sleep(0.05)
            await asyncio.to_thread(mavsdk.destroy)
            return
    _abandoned.append(mavsdk)
    logger.error("MAVSDK not released within %.0f s, abandoned; calls still blocked: %s", timeout_s,
                 ", ".join(executor.running) or "none")
