"""The nanotrack processor's loss and re-acquisition on generated frames (real video: test_nanotrack_real_video.py)."""

from __future__ import annotations

import numpy as np
import pytest

from processors.nanotrack_tracker import NanoTrackProcessor

_RNG = np.random.default_rng(3)
_TARGET = np.repeat(np.repeat(_RNG.integers(0, 255, (4, 6, 3), dtype=np.uint8), 8, axis=0), 8, axis=1)
"""A 48 x 32 px block of coloured squares."""


def _scene(at: tuple[int, int] | None) -> np.ndarray:
    frame = np.full((480, 640, 3), 110, np.uint8)
    if at is not None:
        x, y = at
        frame[y : y + 32, x : x + 48] = _TARGET
    return frame


def _run(processor: NanoTrackProcessor, places: list[tuple[int, int] | None]) -> list[tuple[float, ...] | None]:
    boxes = []
    for place in places:
        processor.photo_processing(_scene(place))
        boxes.append(processor.box)
    return boxes


def _started() -> NanoTrackProcessor:
    processor = NanoTrackProcessor()
    processor.catch_cmd((200, 200, 48, 32))
    _run(processor, [(200, 200)])
    return processor


def test_a_target_that_goes_is_lost_after_lost_after_frames_and_taken_back_where_it_returns() -> None:
    processor = _started()
    moving = [(200 + 3 * i, 200 + 2 * i) for i in range(1, 11)]
    boxes = _run(processor, moving)
    for box, (x, y) in zip(boxes, moving, strict=True):
        assert box is not None and abs(box[0] - x) <= 2 and abs(box[1] - y) <= 2
    gone = _run(processor, [None] * 6)
    assert gone[0] is not None and all(box is None for box in gone[1:])  # lost_after=2: the second frame says so
    assert processor.lost and processor.getPreparedVector() is None
    back = _run(processor, [(232, 222)])  # back beside where it went: NanoTrack's own window finds it
    assert back[0] is not None and abs(back[0][0] - 232) <= 2 and abs(back[0][1] - 222) <= 2


def test_a_target_back_far_from_where_it_went_is_found_by_the_whole_frame_search() -> None:
    processor = _started()
    _run(processor, [(200, 200)] * 5 + [None] * 2)
    assert processor.lost
    far = (520, 60)  # 7 target sizes away: out of NanoTrack's window
    boxes = _run(processor, [far] * processor.wide_every)
    assert all(box is None for box in boxes[:-1])  # the whole frame is searched every wide_every lost frames
    found = boxes[-1]
    assert found is not None and abs(found[0] - far[0]) <= 2 and abs(found[1] - far[1]) <= 2


def test_f2_searches_the_whole_frame_on_the_next_frame() -> None:
    processor = _started()
    _run(processor, [(200, 200)] * 5 + [None] * 2)
    processor.customize_processing(2)
    (found,) = _run(processor, [(520, 60)])
    assert found is not None and abs(found[0] - 520) <= 2 and abs(found[1] - 60) <= 2


def test_f2_on_the_frame_a_search_is_due_searches_once(monkeypatch: pytest.MonkeyPatch) -> None:
    processor = _started()
    _run(processor, [(200, 200)] * 5 + [None] * 2)
    assert processor.lost
    searches: list[np.ndarray] = []
    monkeypatch.setattr(processor, "_search", searches.append)
    _run(processor, [None] * (processor.wide_every - 1))
    processor.customize_processing(2)
    _run(processor, [None])  # the wide_every-th lost frame: its search and F2's are one
    assert len(searches) == 1
