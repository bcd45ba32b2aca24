"""scripts/build_covered_set.py: where the covered stretch lies, and what paints the target over."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tests.scripts import script_module
from uav_tui.evaluation.sequences import Sequence


def _sequence(frames: int, fps: float) -> Sequence:
    return Sequence("s", Path("gt.txt"), np.zeros((frames, 4)), fps=fps)


def test_the_stretch_starts_at_its_share_earlier_near_the_end_and_not_at_all_in_a_short_sequence() -> None:
    with script_module("build_covered_set") as build:
        assert build.stretch(_sequence(120, 10.0), 2.0, 0.4) == range(48, 68)
        assert build.stretch(_sequence(120, 30.0), 2.0, 0.4) == range(30, 90)  # 1 s left after it
        assert build.stretch(_sequence(118, 30.0), 2.0, 0.4) is None  # under 1 s + 2 s + 1 s


def test_the_box_is_painted_over_with_the_patch_beside_it() -> None:
    image = np.zeros((40, 60, 3), np.uint8)
    image[:, :20] = 50  # the background to the left of the box
    image[10:30, 28:40] = 255  # the target
    with script_module("build_covered_set") as build:
        covered = build.cover(image.copy(), np.array([28.0, 10.0, 12.0, 20.0]))
    assert covered.max() < 255 and (covered[:, 43:] == image[:, 43:]).all()  # the box grown by 15 %: to x 42
