"""The platform's tracks over a processor's ``detections`` (issue 50): stable ids through a crossing and a gap, and a
processor's own ids taken or refused. A restarted processor's new numbers: tests/hosting/test_restarts.py."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from skimage import data

from processors.detections import MAX_TRACK_ID
from processors.yolo_detector import YoloDetector
from sources.synthetic import SyntheticSource
from tests.hosting.hosts import BOTH, collect, running_worker
from tests.hosting.sim_cars import GAP_S, track_ids
from uav_tui.hosting.frame_call import call_frame
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.tracks import DetectionTracks


def test_tracks_keep_their_ids_through_a_crossing_and_a_1_s_gap() -> None:
    ids, lefts = track_ids(10, DetectionTracks())  # 10 fps: a detector on a Pi
    before, after = (lefts[min(lefts, key=lambda s: abs(s - edge))] for edge in GAP_S)
    assert (before[0] > before[1]) != (after[0] > after[1])  # cars 0 and 1 crossed during the gap
    assert {car: set(seen) for car, seen in ids.items()} == {0: {0}, 1: {1}, 2: {2}}, ids


def test_a_processors_own_track_ids_are_kept() -> None:
    own = SimpleNamespace(photo_processing=lambda frame: None,
                          detections=[((1, 2, 30, 40), "car", 0.9, 17), {"box": (50, 2, 30, 40), "label": "car",
                                                                         "score": 0.8, "track_id": np.int64(3)}])
    outcome = call_frame(own, None, vector=False, tracks=DetectionTracks())
    assert outcome.detections is not None and [d.track_id for d in outcome.detections] == [17, 3]


@pytest.mark.parametrize("track_id, message", [
    (-1, r"detections\[0\]: track_id -1 must be a whole number in \[0, 1000000\) or None"),
    (MAX_TRACK_ID, r"track_id 1000000 must be"),
    (1.5, r"track_id 1.5 must be"),
    (True, r"track_id True must be"),
    ("7", r"track_id '7' must be"),
])
def test_a_track_id_that_is_not_a_small_whole_number_is_the_processors_error(track_id: object, message: str) -> None:
    bad = SimpleNamespace(photo_processing=lambda frame: None, detections=[((1, 2, 30, 40), "car", 0.9, track_id)])
    outcome = call_frame(bad, None, vector=False, tracks=DetectionTracks())
    assert outcome.detections is None and outcome.raised.startswith("ValueError") and outcome.error is not None
    with pytest.raises(ValueError, match=message):
        raise ValueError(outcome.raised)


def test_one_track_id_on_two_detections_of_a_frame_is_the_processors_error() -> None:
    twice = SimpleNamespace(photo_processing=lambda frame: None,
                            detections=[((1, 2, 30, 40), "car", 0.9, 4), ((90, 2, 30, 40), "car", 0.9, 4)])
    outcome = call_frame(twice, None, vector=False, tracks=DetectionTracks())
    assert outcome.detections is None and "track_id 4 is on two detections of one frame" in outcome.raised



@BOTH
async def test_either_host_numbers_a_processors_detections(isolation: str) -> None:
    source = SyntheticSource(fps=100, width=160, height=120)
    results: list[ProcessedFrame] = []
    assert source.open()
    try:
        async with running_worker(isolation, "tests.recording.recorder_processors:FixedBox", results.append) as worker:
            worker.attach(source.buffer)
            await collect(worker, results, 5)
    finally:
        source.close()
    assert {found.track_id for r in results[:5] for found in r.outcome.detections or ()} == {0}  # one object, one track


def test_the_yolo_references_person_is_one_track_as_she_moves() -> None:
    """The shipped ``yolo`` as it runs by default (Yolo-Fastest on OpenCV's Darknet loader every third frame, optical
    flow between) on a photograph shifted 4 px a frame."""
    photo = np.ascontiguousarray(data.astronaut()[..., ::-1])
    detector, tracks, ids = YoloDetector(), DetectionTracks(), []
    for n in range(4):
        outcome = call_frame(detector, np.roll(photo, 4 * n, axis=1), vector=False, tracks=tracks,
                             seen_ns=n * 100_000_000)  # 10 fps
        assert outcome.error is None and outcome.detections
        ids.append(next(found.track_id for found in outcome.detections if found.label == "person"))
    assert len(set(ids)) == 1 and ids[0] is not None, ids
