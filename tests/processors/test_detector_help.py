"""The detector's help on real video: the target's class at selection, and the target found again after a cover."""

from __future__ import annotations

import itertools

import cv2
import numpy as np

from processors import target_search
from processors.detector_help import DetectorHelp
from tests.scripts import script_module
from tests.videos import aerial_set
from uav_tui.evaluation.sequences import load_sequence
from uav_values.box import Box

SEQUENCE, COVERED, BACK = "uav123_10fps-person12_1", range(48, 68), 68
"""A walker, hidden 2 s from 40 % into the clip (as scripts/build_covered_set.py hides him), back at frame 68."""


def test_a_covered_walker_is_not_offered_and_is_found_again_when_he_is_back() -> None:
    sequence = load_sequence(aerial_set(SEQUENCE))
    frames = list(itertools.islice(sequence.frames(), BACK + 1))
    gt = [tuple(float(v) for v in row) for row in sequence.gt]
    helper = DetectorHelp(every=1)
    assert helper.select(frames[0], gt[0]) == "person"
    appearance = target_search.template(cv2.cvtColor(frames[0], cv2.COLOR_BGR2GRAY), gt[0])
    assert appearance is not None
    last = gt[COVERED.start - 1]
    with script_module("build_covered_set") as build:
        hidden = [build.cover(frames[i].copy(), np.array(gt[i])) for i in COVERED]
    for image in hidden:
        assert helper.best(image, last, _look(image, appearance), 0.3) is None, "a person under the cover"
    found = helper.best(frames[BACK], last, _look(frames[BACK], appearance), 0.3)
    assert found is not None and _inside(found[0], gt[BACK]), found  # where NanoTrack is tried
    assert helper.ms > 0


def test_without_a_detection_on_the_selection_there_is_no_class_and_no_detection() -> None:
    sequence = load_sequence(aerial_set(SEQUENCE))
    first = next(sequence.frames())
    helper = DetectorHelp(every=1)
    assert helper.select(first, (0.0, 0.0, 30.0, 30.0)) is None  # the corner: road, no object
    helper.ms = 0.0
    assert helper.candidates(first, tuple(float(v) for v in sequence.gt[0])) == [] and helper.ms == 0.0


def _inside(box: Box, truth: Box) -> bool:
    """The centre of ``box`` is within ``truth``."""
    cx, cy = box[0] + box[2] / 2, box[1] + box[3] / 2
    return truth[0] <= cx <= truth[0] + truth[2] and truth[1] <= cy <= truth[1] + truth[3]


def _look(image: np.ndarray, appearance: np.ndarray):  # noqa: ANN202 - a closure
    gray = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)

    def look(box: Box) -> float:
        found = target_search.search(gray, [appearance], box, 0.25)
        return found.score if found is not None else -1.0

    return look
