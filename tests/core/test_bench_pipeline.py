"""``scripts/bench_pipeline.py`` compares like with like: its bare loop replays exactly the frames the platform
processed, from the frame the target was selected on, and says so only when the tracker did the same on each."""

from __future__ import annotations

import asyncio
import dataclasses
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import cv2
import numpy as np
import pytest

from tests.scripts import script_module
from uav_tui.evaluation.sequences import find_sequences

ROOT = Path(__file__).resolve().parents[2]
SIZE = (320, 240)


@pytest.fixture(scope="module")
def bench() -> Iterator[ModuleType]:
    with script_module("bench_pipeline") as module:
        yield module


def boat_video(bench: ModuleType, aerial_tracking: Path, path: Path) -> tuple[int, int, int, int]:
    """Write the real boat sequence at :data:`SIZE`, forward then backward so that its loop has no cut; return
    its ground-truth box on the first frame, scaled.

    The tracker keeps this boat from whichever early frame the ROI lands on (a race, as for an operator). The
    middle of the bench's own footage, cut every 25 frames, was lost for good when the ROI landed on frame 2 or
    3, which left no tracked frame to compare."""
    sequence = find_sequences([aerial_tracking / "uav123_10fps-boat5"])[0]
    originals = sequence.frames()
    first = next(originals)
    frames = [cv2.resize(frame, SIZE, interpolation=cv2.INTER_AREA) for frame in (first, *originals)]
    bench.make_video(path, frames + frames[-2:0:-1], *SIZE)
    scale = np.array([SIZE[0] / first.shape[1], SIZE[1] / first.shape[0]] * 2)
    x, y, w, h = (sequence.gt[0] * scale).astype(int)
    return int(x), int(y), int(w), int(h)


def test_the_bare_loop_replays_the_frames_the_platform_tracked(aerial_tracking: Path, bench: ModuleType,
                                                               tmp_path: Path) -> None:
    video = tmp_path / "boat.mp4"
    roi = boat_video(bench, aerial_tracking, video)
    run, replayed = asyncio.run(bench.platform_run(f"file:{video}?realtime=0", "csrt", "process", 1.0, roi,
                                                   warm_up_s=1.0))
    assert replayed.selected is not None and replayed.selected < replayed.first
    assert run["frames"] == replayed.last - replayed.first + 1 == len(replayed.boxes)  # lockstep: none skipped
    assert any(replayed.boxes)  # it tracked something

    bare = bench.bare_loop(video, "csrt", replayed, roi, None)
    assert bare["frames"] == run["frames"]
    differs = bare["first_different_frame"]
    assert differs is None, (f"the bare loop tracked something else from frame {differs} on (selected on "
                             f"{replayed.selected}, measured from {replayed.first}); the platform tracked "
                             f"{replayed.boxes[differs - replayed.first:][:3]} there")

    selected_later = dataclasses.replace(replayed, selected=replayed.selected + 5)
    assert bench.bare_loop(video, "csrt", selected_later, roi, None)["first_different_frame"] is not None
