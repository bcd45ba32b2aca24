"""The colours of a covered target's box: like its surroundings, not like the target (real video, and a plain case)."""

from __future__ import annotations

import itertools
import statistics

import numpy as np
import pytest

from processors import colour_contrast
from processors.nanotrack_tracker import COLOUR_RISE
from tests.scripts import script_module
from tests.videos import aerial_set
from uav_tui.evaluation.sequences import load_sequence

COVERED = {"uav123_10fps-car14": range(120, 140), "uav123_10fps-group3_2": range(60, 80)}
"""Where scripts/build_covered_set.py hides each target (2 s from 40 % into the clip)."""


def test_a_box_on_the_target_is_unlike_its_surroundings_and_one_on_the_background_is_like_them() -> None:
    field = np.zeros((120, 160, 3), np.uint8)
    field[:] = (40, 160, 40)  # green
    field[40:80, 60:100] = (30, 30, 200)  # a red target
    target = colour_contrast.box_histogram(field, (60, 40, 40, 40))
    assert target is not None
    on_target = colour_contrast.background_likeness(field, (60, 40, 40, 40), target)
    on_grass = colour_contrast.background_likeness(field, (10, 10, 30, 30), target)
    assert on_target is not None and on_grass is not None
    assert on_target < -0.5 and on_grass > 0.5
    assert colour_contrast.background_likeness(field, (159, 0, 8, 8), target) is None  # 1 px inside the frame


@pytest.mark.parametrize("name", sorted(COVERED))
def test_a_covered_box_looks_like_the_background_by_more_than_colour_rise(name: str) -> None:
    sequence = load_sequence(aerial_set(name))
    covered = COVERED[name]
    frames = list(itertools.islice(sequence.frames(), covered.stop))
    target = colour_contrast.box_histogram(frames[0], tuple(sequence.gt[0]))
    assert target is not None

    def likeness(image: np.ndarray, index: int) -> float:
        found = colour_contrast.background_likeness(image, tuple(sequence.gt[index]), target)
        assert found is not None
        return found

    usual = statistics.median(likeness(frames[i], i) for i in range(covered.start - 10, covered.start))
    with script_module("build_covered_set") as build:
        hidden = [likeness(build.cover(frames[i].copy(), sequence.gt[i]), i) for i in covered]
    assert min(hidden) >= usual + COLOUR_RISE, f"usual {usual:.2f}, covered {np.round(hidden, 2)}"
