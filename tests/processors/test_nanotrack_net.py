"""NanoTrackNet: NanoTrack v2 run here, its scale penalty independent of where the target is, its hold, its map."""

from __future__ import annotations

import numpy as np

from processors.nanotrack_net import HOLD_SHARPNESS, RIVAL_CELLS, NanoTrackNet, rival, sharpness

_RNG = np.random.default_rng(1)
_TARGET = np.repeat(np.repeat(_RNG.integers(0, 255, (4, 6, 3), dtype=np.uint8), 8, axis=0), 8, axis=1)
"""A 48 x 32 px block of coloured squares."""


def _scene(x: int | None, y: int | None, *others: tuple[int, int]) -> np.ndarray:
    frame = np.full((720, 1280, 3), 110, np.uint8)
    for ox, oy in ([(x, y)] if x is not None and y is not None else []) + list(others):
        frame[oy : oy + 32, ox : ox + 48] = _TARGET
    return frame


def test_follows_a_target_the_same_wherever_it_is_in_the_frame() -> None:
    # OpenCV's TrackerNano compares candidate sizes with the target's position: it moves this box 7 px right at
    # (150, 150) and 6 px at the other two places
    moved = []
    for x, y in [(150, 150), (1000, 550), (600, 40)]:
        tracker = NanoTrackNet()
        tracker.init(_scene(x, y), (x, y, 48, 32))
        ok, box = tracker.update(_scene(x + 6, y + 4))
        assert ok and tracker.sharpness > 2 * HOLD_SHARPNESS
        moved.append((box[0] - x, box[1] - y, box[2], box[3]))
    assert moved[0] == moved[1] == moved[2]
    dx, dy, w, h = moved[0]
    assert abs(dx - 6) <= 1 and abs(dy - 4) <= 1 and abs(w - 48) <= 2 and abs(h - 32) <= 2


def test_holds_the_box_while_nothing_like_the_target_is_there_and_follows_it_back() -> None:
    tracker = NanoTrackNet()
    tracker.init(_scene(600, 300), (600, 300, 48, 32))
    _, box = tracker.update(_scene(None, None))
    assert tracker.sharpness < HOLD_SHARPNESS and box == (600, 300, 48, 32)
    _, box = tracker.update(_scene(606, 304))
    assert tracker.sharpness > HOLD_SHARPNESS and abs(box[0] - 606) <= 1 and abs(box[1] - 304) <= 1


def test_a_target_at_the_frame_edge_is_searched_in_a_padded_window() -> None:
    tracker = NanoTrackNet()
    tracker.init(_scene(0, 0), (0, 0, 48, 32))
    _, box = tracker.update(_scene(4, 2))
    assert abs(box[0] - 4) <= 1 and abs(box[1] - 2) <= 1


def test_sharpness_is_high_for_one_peak_lower_for_two_and_low_for_none() -> None:
    rows, cols = np.mgrid[:16, :16]

    def blob(row: int, col: int) -> np.ndarray:
        return np.exp(-((rows - row) ** 2 + (cols - col) ** 2) / 4.5)

    one, two = sharpness(blob(8, 8)), sharpness(np.maximum(blob(8, 8), blob(3, 3)))
    assert one > 2 * HOLD_SHARPNESS and two < 0.5 * one
    assert sharpness(_RNG.uniform(0.0, 1.0, (16, 16))) < HOLD_SHARPNESS


def test_rival_is_the_highest_peak_away_from_the_best_and_not_its_own_flank() -> None:
    response = np.zeros((16, 16), np.float32)
    response[8, 8], response[8, 8 + RIVAL_CELLS] = 1.0, 0.9  # a flank within RIVAL_CELLS: the same place
    assert rival(response) == 0.0
    response[1, 1] = 0.6
    assert rival(response) == np.float32(0.6)


def test_a_look_alike_in_the_window_is_a_rival_and_move_to_searches_elsewhere() -> None:
    tracker = NanoTrackNet()
    tracker.init(_scene(600, 300), (600, 300, 48, 32))
    tracker.update(_scene(600, 300))
    alone = tracker.rival
    tracker.update(_scene(600, 300, (600 - 56, 300 - 44)))  # another one 1.8 target sizes away
    assert alone < 0.1 and tracker.rival > 0.5
    tracker.move_to((1000, 500, 48, 32))
    _, box = tracker.update(_scene(1006, 504))
    assert tracker.sharpness > HOLD_SHARPNESS and abs(box[0] - 1006) <= 1 and abs(box[1] - 504) <= 1


def test_a_look_alike_that_overtakes_the_target_on_the_map_is_not_followed() -> None:
    tracker = NanoTrackNet()
    tracker.init(_scene(600, 300), (600, 300, 48, 32))
    tracker.update(_scene(600, 300, (544, 256)))  # a look-alike beside the target: the box stays on the target
    assert tracker.rival > 0.5
    for _ in range(2):  # the target hidden: the look-alike is the map's sharp peak, and the box does not go there
        _, box = tracker.update(_scene(None, None, (544, 256)))
        assert tracker.sharpness > HOLD_SHARPNESS and box == (600, 300, 48, 32)
    _, box = tracker.update(_scene(606, 304, (544, 256)))  # the target back: followed
    assert abs(box[0] - 606) <= 1 and abs(box[1] - 304) <= 1
