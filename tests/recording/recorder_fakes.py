"""A stand-in for UavCore with the parts the Recorder attaches to (real EventLog, TelemetryManager and
ActiveCamera)."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from sources.buffer import Frame
from uav_tui.camera.active import ActiveCamera
from uav_tui.config import CameraConfig
from uav_tui.events import EventLog
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.wire import FrameOutcome
from uav_tui.recording import Recorder
from uav_tui.relays.contract import HandledFrame
from uav_values.box import PixelBox
from uav_values.camera import CameraModel
from uav_values.detections import Detected


@dataclass
class _Worker:
    current: Frame | None = None
    busy_s: float = 0.0


@dataclass
class Draft:
    """What a test's stand-in for the processor is given (``frame``) and sets: its outcome's fields and the gate's
    decision."""

    frame: Frame
    vector: Any = None
    error: str | None = None
    box: PixelBox | None = None
    detections: tuple[Detected, ...] | None = None
    decision: str = ""


class FakeCore:
    """Processes frames the way the worker does: ``current`` and ``busy_s`` set while the processor runs."""

    def __init__(self) -> None:
        self.events = EventLog()
        self.telemetry = TelemetryManager(None)
        self.worker = _Worker()
        self.active_camera = ActiveCamera(CameraConfig(), self.events, lambda coro, name: None)
        self._listeners: list[Callable[[HandledFrame], None]] = []

    @property
    def camera(self) -> CameraModel | None:
        return self.active_camera.model

    @camera.setter
    def camera(self, model: CameraModel | None) -> None:
        self.active_camera.model = model

    def attach(self, recorder: Recorder) -> None:
        """Attach ``recorder`` as the core does: to its parts, then as a frame listener."""
        recorder.attach(self.events, self.telemetry, self.worker, self.active_camera)  # type: ignore[arg-type]
        self.add_frame_listener(recorder.on_frame)

    def add_frame_listener(self, listener: Callable[[HandledFrame], None]) -> None:
        self._listeners.append(listener)

    def process(self, image, seq: int, processor: Callable[[Draft], None]) -> HandledFrame:
        """Run ``processor(draft)`` as photo_processing would run, then deliver the frame with the draft's outcome."""
        frame = Frame(image, seq, time.monotonic_ns(), time.time_ns())
        draft = Draft(frame)
        self.worker.current, self.worker.busy_s = frame, 0.001
        try:
            processor(draft)
        finally:
            self.worker.current, self.worker.busy_s = None, 0.0
        outcome = FrameOutcome(frame.t_mono_ns + 500_000, frame.t_mono_ns + 3_000_000, vector=draft.vector,
                               box=draft.box, detections=draft.detections, error=draft.error)
        result = HandledFrame(ProcessedFrame(frame, outcome), draft.decision)
        for listener in self._listeners:
            listener(result)
        return result
