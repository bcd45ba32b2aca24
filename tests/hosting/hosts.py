"""What the host tests share: a host of either kind, started, and waiting on its results."""

from __future__ import annotations

import asyncio
import time
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from typing import Any

import numpy as np
import pytest

from processors import load_processor
from sources.buffer import FrameBuffer
from uav_tui.events import EventLog
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.process_host import SubprocessHost
from uav_tui.hosting.thread_host import ThreadHost

Worker = ThreadHost | SubprocessHost
BOTH = pytest.mark.parametrize("isolation", ["process", "thread"])
"""Run a test with the processor in its own process and on a platform thread."""

SLOW = '''
import os, threading, time

class Slow:
    def __init__(self, delay=0.03):
        self.tmMgr = None
        self.delay = delay
        self.threads = set()
        self.buttons = []

    def photo_processing(self, frame):
        self.threads.add(threading.get_ident())
        time.sleep(self.delay)

    def customize_processing(self, id):
        self.threads.add(threading.get_ident())
        self.buttons.append(id)
        return os.getpid(), sorted(self.threads), self.buttons
'''


async def until(condition: Callable[[], object], what: str, timeout: float = 10) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        await asyncio.sleep(0.005)


@asynccontextmanager
async def running_worker(isolation: str, spec: str, on_result: Callable[[ProcessedFrame], None],
                         kwargs: dict[str, Any] | None = None) -> AsyncIterator[Worker]:
    """A started worker of either kind (its ``run()`` task is the caller's)."""
    if isolation == "thread":
        worker: Worker = ThreadHost(load_processor(spec, kwargs), on_result)
    else:
        worker = await SubprocessHost.start(spec, kwargs or {}, on_result, events=EventLog(), on_fault=print)
    try:
        yield worker
    finally:
        worker.close()


async def collect(worker: Worker, results: list[ProcessedFrame], count: int, timeout: float = 10) -> None:
    task = asyncio.create_task(worker.run())
    deadline = time.monotonic() + timeout
    try:
        while len(results) < count and time.monotonic() < deadline:
            await asyncio.sleep(0.01)
    finally:
        task.cancel()
        await asyncio.gather(task, return_exceptions=True)  # its stop ran whole: nothing of it left to the loop's end
    assert len(results) >= count, f"only {len(results)} frames processed"


async def one_at_a_time(worker: Worker, buffer: FrameBuffer, results: list[ProcessedFrame], frames: int) -> None:
    """Put ``frames`` small frames, each once the one before was processed (so none is skipped)."""
    worker.attach(buffer)
    task = asyncio.create_task(worker.run())
    try:
        for n in range(1, frames + 1):
            buffer.put(np.zeros((4, 4, 3), np.uint8))
            await until(lambda n=n: len(results) == n, f"frame {n} processed")
    finally:
        task.cancel()
        await asyncio.gather(task, return_exceptions=True)
