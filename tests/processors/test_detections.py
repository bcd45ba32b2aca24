"""The optional ``detections`` attribute, read at the boundary: what is taken, and what is the processor's error."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from skimage import data

from processors.detections import MAX_DETECTIONS, read_detections
from processors.yolo_detector import YoloDetector
from uav_tui.hosting.frame_call import call_frame
from uav_values.detections import Detected, Detection


def _with(detections: object) -> SimpleNamespace:
    return SimpleNamespace(detections=detections, box=(1, 2, 3, 4), photo_processing=lambda frame: None)


def test_the_three_forms_are_taken_as_whole_pixels_label_and_score() -> None:
    found = read_detections(_with([
        Detection((10.4, 20.6, 30.0, 40.2), np.float32(0.9), 0, "person"),  # an object with box, label, score
        {"box": [1, 2, 3, 4], "label": "car", "score": 0.5},
        ((5, 6, 0.4, 8), "boat", 1),  # under a pixel wide: one pixel
    ]))
    assert found == (Detected((10, 21, 30, 40), "person", pytest.approx(0.9)), Detected((1, 2, 3, 4), "car", 0.5),
                     Detected((5, 6, 1, 8), "boat", 1.0))
    assert read_detections(_with([])) == ()
    assert read_detections(_with(None)) is None and read_detections(SimpleNamespace()) is None


@pytest.mark.parametrize("detections, message", [
    ("person", "detections is str: set a list"),
    ({"box": (1, 2, 3, 4)}, "detections is dict"),
    (42, "detections is int"),
    ([(1, 2, 3, 4)], r"detections\[0\] is tuple"),
    ([((1, 2, 3, 4), "car", math.nan)], r"detections\[0\]: score nan must be in \[0, 1\]"),
    ([((1, 2, 3, 4), "car", 0.5), ((1, 2, 3, 4), "car", 1.5)], r"detections\[1\]: score 1.5 must be in \[0, 1\]"),
    ([((1, 2, 3, 4), "car", "high")], r"detections\[0\]: score 'high' is not a number"),
    ([((1, 2, math.inf, 4), "car", 0.5)], r"detections\[0\]: box .* must be finite"),
    ([((1, 2, 0, 4), "car", 0.5)], r"positive width and height"),
    ([((1, 2, 3), "car", 0.5)], r"detections\[0\]: box \(1, 2, 3\) is not 4 numbers"),
    ([((1, 2, 3, 4), 7, 0.5)], r"detections\[0\]: label 7 must be a text"),
    ([((1, 2, 3, 4), "x" * 65, 0.5)], r"label 'xxx.* must be a text of 1 to 64"),
    ([((1, 2, 3, 4), "car", 0.5)] * (MAX_DETECTIONS + 1), rf"{MAX_DETECTIONS + 1} items, at most {MAX_DETECTIONS}"),
])
def test_malformed_detections_are_the_processors_error_and_none_is_kept(detections: object, message: str) -> None:
    with pytest.raises((TypeError, ValueError), match=message):
        read_detections(_with(detections))
    outcome = call_frame(_with(detections), None, vector=False)  # as every host calls it
    assert outcome.detections is None and outcome.raised and outcome.error is not None
    assert outcome.box == (1, 2, 3, 4)  # read first: a bad list does not lose the box


def test_the_yolo_reference_reports_its_detections_this_way() -> None:
    frame = np.ascontiguousarray(data.astronaut()[..., ::-1])
    detector = YoloDetector(mode="paper")
    detector.photo_processing(frame.copy())
    found = read_detections(detector)
    assert found is not None and found[0].label == "person" and found[0].score >= 0.4
    # A crowd: more boxes than the bound, most confident first; it reports the most confident MAX_DETECTIONS.
    crowd = [Detection((i, i, 10.0, 10.0), 1 - i / 100, 0, "person") for i in range(50)]
    detector.backend.detect = lambda image: list(crowd)  # type: ignore[method-assign]
    detector.photo_processing(frame.copy())
    found = read_detections(detector)
    assert found is not None and [d.score for d in found] == [d.score for d in crowd[:MAX_DETECTIONS]]
