"""The recorded video survives SIGKILL, and frames it could not take are counted and named in its index."""

from __future__ import annotations

import functools
import signal
import subprocess
import sys
import time
from pathlib import Path

import av
import pandas as pd

from tests.core.flight_helpers import wait_until
from uav_tui.config import Config, with_overrides
from uav_tui.core import UavCore
from uav_tui.recorded import dataset
from uav_tui.recording import recorder as recorder_module
from uav_tui.recording.video import VideoStage
from uav_tui.recording.writer import MB, DiskWriter

IDLE = "tests.replay.replay_processors:Idle"


def _decoded(path: Path) -> int:
    with av.open(str(path)) as container:
        return sum(1 for _ in container.decode(video=0))


def _indexed(run_dir: Path) -> pd.DataFrame:
    return pd.read_csv(run_dir / "video.csv", dtype={"video_frame": "Int64", "frame_id": "Int64"})


def test_sigkill_leaves_a_video_playable_up_to_the_last_flush(tmp_path):
    command = [sys.executable, "-m", "uav_tui", "--no-ui", "--source", "synthetic:?fps=30", "--processor", IDLE,
               "--runs-dir", str(tmp_path)]
    process = subprocess.Popen(command, cwd=Path(__file__).resolve().parents[2], stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        while not any(len(path.read_bytes().splitlines()) > 60 for path in tmp_path.glob("*/video.csv")):
            assert process.poll() is None and time.monotonic() < deadline, "the recording never got going"
            time.sleep(0.1)
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait(10)
    (run_dir,) = tmp_path.iterdir()
    assert "end_wall_ns" not in dataset.load(run_dir).info  # it really was killed, not closed
    index = _indexed(run_dir)
    indexed = index["video_frame"].dropna()
    assert len(indexed) > 30 and indexed.tolist() == list(range(len(indexed)))
    assert _decoded(run_dir / "video.ts") >= len(indexed)  # every indexed frame plays; later ones may too


class SlowVideoStage(VideoStage):
    """Takes 0.1 s per frame, as a board far too slow for its camera would."""

    def _encode(self, item):
        time.sleep(0.1)
        return super()._encode(item)


async def test_frames_the_video_cannot_take_are_dropped_counted_and_indexed(tmp_path, monkeypatch):
    monkeypatch.setattr(recorder_module, "VideoStage", SlowVideoStage)
    monkeypatch.setattr(recorder_module, "DiskWriter", functools.partial(DiskWriter, max_image_bytes=4 * MB))
    config = with_overrides(Config(), source="synthetic:?fps=30", runs_dir=str(tmp_path), processor=IDLE)
    core = UavCore(config)
    await core.start()
    stats = core.worker.stats
    await wait_until(lambda: stats.frames_processed >= 60, 20, "60 processed frames")  # 2 s at 30 FPS, unloaded
    await core.stop()

    assert stats.frames_processed >= 60 and stats.frames_skipped <= 0.15 * stats.frames_processed
    index = _indexed(core.recorder.run_dir)
    dropped = index[index["dropped"].notna()]
    assert len(dropped) == core.recorder.writer.dropped["queue_full"] > 0.3 * len(index)
    assert set(dropped["dropped"]) == {"queue_full"} and dropped["video_frame"].isna().all()
    kept = index["video_frame"].dropna()
    assert kept.tolist() == list(range(len(kept))) and _decoded(core.recorder.run_dir / "video.ts") == len(kept)
