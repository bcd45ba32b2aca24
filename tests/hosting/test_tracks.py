"""The platform's tracks over a processor's ``detections`` (issue 50): stable ids through a crossing and a gap, a
processor's own ids taken or refused, and new numbers after a restart."""

from __future__ import annotations

import asyncio
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from processors.detections import MAX_TRACK_ID
from sources import open_source
from tests.core.flight_helpers import wait_until
from tests.hosting.sim_cars import GAP_S, track_ids
from tests.videos import create_video_file
from uav_tui.events import EventLog
from uav_tui.hosting.frame_call import call_frame
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.process_host import SubprocessHost
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


DETECTS_AND_DIES_ONCE = '''
import os
from pathlib import Path

class DetectsAndDiesOnce:
    """One car standing still; dies on its third frame, the first time it runs."""

    def __init__(self, marker):
        self.marker, self.frames, self.detections = Path(marker), 0, []

    def photo_processing(self, frame):
        self.frames += 1
        if self.frames == 3 and not self.marker.exists():
            self.marker.touch()
            os._exit(3)
        self.detections = [((10, 10, 20, 20), "car", 0.9)]
'''


async def test_a_restarted_processors_tracks_do_not_take_the_numbers_recorded_before(tmp_path: Path) -> None:
    (tmp_path / "detects.py").write_text(DETECTS_AND_DIES_ONCE)
    video = create_video_file(tmp_path / "clip.mp4", width=64, height=48)
    source = open_source(f"file:{video}?realtime=0")
    results: list[ProcessedFrame] = []
    worker = await SubprocessHost.start(f"{tmp_path}/detects.py:DetectsAndDiesOnce", {"marker": str(tmp_path / "x")},
                                       results.append, events=EventLog(), on_fault=print, first_backoff_s=0.05)
    worker.attach(source.buffer)
    task = asyncio.create_task(worker.run())
    try:
        await wait_until(lambda: len(results) >= 6, 30, "frames from the restarted processor")
    finally:
        task.cancel()
        await asyncio.gather(task, return_exceptions=True)
        source.close()
    ids = [(r.frame.seq, r.detections[0].track_id) for r in results if r.detections]
    assert ids[:2] == [(1, 0), (2, 0)] and {i for seq, i in ids if seq > 3} == {1}, ids  # the car again: a new track
