"""The processor worker: every call into the researcher's code runs on one thread, newest frame first."""

from __future__ import annotations

import asyncio
import logging
import time
import traceback
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any

from processors import LoadedProcessor
from sources.buffer import Frame, FrameBuffer
from uav_tui.stats import PipelineStats, RollingStats

logger = logging.getLogger(__name__)


@dataclass(slots=True)
class ProcessedFrame:
    """One frame's trip through the processor, with the time of each stage (monotonic ns)."""

    frame: Frame
    """The frame as captured; the processor may have drawn its overlay on ``frame.image``."""
    t_start_ns: int
    t_end_ns: int = 0
    t_vector_ns: int = 0
    """When getPreparedVector returned (0 if the processor has none)."""
    vector: Any = None
    """What getPreparedVector returned, unchecked (the autonomy gate validates it)."""
    error: str | None = None
    """Traceback text if the processor raised."""
    decision: str = ""
    """What the autonomy gate did with the vector: ``executed`` or why not."""
    extra: dict[str, Any] = field(default_factory=dict)
    """Fields the processor stored with ``tmMgr.save(frame, **extra)`` for this frame."""
    saved: bool = False
    """True when the processor saved this frame's image."""


class ProcessorWorker:
    """Runs a processor on one dedicated thread, always on the newest frame of a buffer.

    The loop side (``run``) waits for a frame, hands it to the thread with ``run_in_executor`` and
    gets the result back; frames that arrive meanwhile replace each other in the buffer, so a slow
    processor skips frames and never queues them. ``call`` runs an operator command
    (``catch_cmd``, ``customize_processing``) on the same thread, between two frames.
    """

    def __init__(self, processor: LoadedProcessor, on_result: Callable[[ProcessedFrame], None]) -> None:
        self.processor = processor
        self.stats = RollingStats()
        self.current: ProcessedFrame | None = None
        """The frame being processed (read on the processor thread by ``tmMgr.save``)."""
        self.last: ProcessedFrame | None = None
        """The newest finished frame."""
        self.consecutive_errors = 0
        self._on_result = on_result
        self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="processor")
        self._buffer: FrameBuffer | None = None
        self._new_frame = asyncio.Event()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._busy_since_ns: int | None = None

    # -- loop side -------------------------------------------------------------------------------

    def attach(self, buffer: FrameBuffer) -> None:
        """Take frames from ``buffer`` from now on (a new source)."""
        if self._buffer is not None:
            self._buffer.remove_listener(self._on_frame)
        self._buffer = buffer
        self.stats.restart_sequence()
        buffer.add_listener(self._on_frame)
        self._new_frame.set()

    async def run(self) -> None:
        """Process frames until cancelled."""
        self._loop = asyncio.get_running_loop()
        last_seq, last_buffer = 0, None
        while True:
            await self._new_frame.wait()
            self._new_frame.clear()
            buffer = self._buffer
            frame = buffer.latest() if buffer is not None else None
            if frame is None:
                continue
            if buffer is not last_buffer:
                last_seq, last_buffer = 0, buffer
            if frame.seq <= last_seq:
                continue
            last_seq = frame.seq
            result = await self._loop.run_in_executor(self._executor, self._process, frame)
            self.stats.add(frame.seq, frame.t_mono_ns, result.t_start_ns, result.t_end_ns,
                           result.t_vector_ns or result.t_end_ns)
            self.last = result
            self._on_result(result)

    async def call(self, method: str, *args: Any) -> Any:
        """Call ``processor.<method>(*args)`` on the processor thread; its exception propagates."""
        bound = getattr(self.processor.instance, method)
        return await asyncio.get_running_loop().run_in_executor(self._executor, bound, *args)

    async def replace(self, processor: LoadedProcessor) -> LoadedProcessor:
        """Swap in another processor between two frames; returns the old one."""
        def swap() -> LoadedProcessor:
            old, self.processor = self.processor, processor
            self.consecutive_errors = 0
            return old
        return await asyncio.get_running_loop().run_in_executor(self._executor, swap)

    def snapshot(self) -> PipelineStats:
        captured = self._buffer.captured if self._buffer is not None else 0
        return self.stats.snapshot(captured, self._busy_since_ns)

    @property
    def busy_s(self) -> float:
        """Seconds the current call into the processor has been running (0 when idle)."""
        since = self._busy_since_ns
        return (time.monotonic_ns() - since) / 1e9 if since else 0.0

    def close(self) -> None:
        """Detach and let the thread finish its current call (a hung processor is abandoned)."""
        if self._buffer is not None:
            self._buffer.remove_listener(self._on_frame)
        self._executor.shutdown(wait=False, cancel_futures=True)

    def _on_frame(self, frame: Frame) -> None:  # capture thread
        loop = self._loop
        if loop is not None and not loop.is_closed():
            loop.call_soon_threadsafe(self._new_frame.set)

    # -- processor thread ------------------------------------------------------------------------

    def _process(self, frame: Frame) -> ProcessedFrame:
        instance = self.processor.instance
        start = time.monotonic_ns()
        self._busy_since_ns = start
        result = ProcessedFrame(frame=frame, t_start_ns=start)
        self.current = result
        try:
            instance.photo_processing(frame.image)
            result.t_end_ns = time.monotonic_ns()
            if "getPreparedVector" in self.processor.info.capabilities:
                result.vector = instance.getPreparedVector()
                result.t_vector_ns = time.monotonic_ns()
            self.consecutive_errors = 0
        except Exception:  # noqa: BLE001 - counted and reported, never fatal
            result.t_end_ns = result.t_end_ns or time.monotonic_ns()
            result.error = traceback.format_exc()
            self.stats.errors += 1
            self.consecutive_errors += 1
        finally:
            self._busy_since_ns = None
        return result
