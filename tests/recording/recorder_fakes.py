"""A stand-in for UavCore with the parts the Recorder attaches to (real EventLog and TelemetryManager)."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from sources.buffer import Frame
from uav_tui.events import EventLog
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.hosting.host import ProcessedFrame


@dataclass
class _Worker:
    current: ProcessedFrame | None = None
    busy_s: float = 0.0


class FakeCore:
    """Processes frames the way the worker does: ``current`` and ``busy_s`` set while the processor runs."""

    def __init__(self) -> None:
        self.events = EventLog()
        self.telemetry = TelemetryManager(None)
        self.worker = _Worker()
        self.source = None
        self.camera = None
        self._listeners: list[Callable[[ProcessedFrame], None]] = []

    def current_frame(self) -> ProcessedFrame | None:
        return self.worker.current

    def add_frame_listener(self, listener: Callable[[ProcessedFrame], None]) -> None:
        self._listeners.append(listener)

    def process(self, image, seq: int, processor: Callable[[ProcessedFrame], None]) -> ProcessedFrame:
        """Run ``processor(result)`` as photo_processing would run, then deliver the result."""
        frame = Frame(image, seq, time.monotonic_ns(), time.time_ns())
        result = ProcessedFrame(frame, t_start_ns=frame.t_mono_ns + 500_000)
        self.worker.current, self.worker.busy_s = result, 0.001
        try:
            processor(result)
        finally:
            self.worker.current, self.worker.busy_s = None, 0.0
        result.t_end_ns = result.t_end_ns or frame.t_mono_ns + 3_000_000
        for listener in self._listeners:
            listener(result)
        return result
