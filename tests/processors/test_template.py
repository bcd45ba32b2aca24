"""The paper's template processor: mean brightness, one tmMgr.save every Nth frame."""

from __future__ import annotations

from typing import Any

import numpy as np

from processors.template import MeanBrightnessProcessor


class RecordingTelemetry:
    """Stands in for the TelemetryManager's save() only: records what the processor saves."""

    def __init__(self) -> None:
        self.saved: list[tuple[np.ndarray, dict[str, Any]]] = []

    def save(self, frame: np.ndarray, **extra: Any) -> None:
        self.saved.append((frame, extra))


def test_measures_brightness_and_saves_every_nth_frame() -> None:
    processor = MeanBrightnessProcessor(save_every=3)
    processor.tmMgr = RecordingTelemetry()
    for value in range(1, 7):
        processor.photo_processing(np.full((8, 8, 3), value * 10, np.uint8))
    assert processor.brightness == 60.0
    assert [extra["brightness"] for _, extra in processor.tmMgr.saved] == [30.0, 60.0]


def test_works_without_a_platform() -> None:
    processor = MeanBrightnessProcessor()
    processor.photo_processing(np.zeros((2, 2, 3), np.uint8))
    assert processor.brightness == 0.0
