"""The disk writer under pressure: a slow disk, a full disk, a size cap, and SIGKILL mid-run."""

from __future__ import annotations

import asyncio
import errno
import functools
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pandas as pd

from uav_tui.config import Config, with_overrides
from uav_tui.core import UavCore
from uav_tui.recorded import dataset
from uav_tui.recorded.runs_cli import list_runs
from uav_tui.recording import recorder as recorder_module
from uav_tui.recording.writer import MB, DiskWriter, Row

REPO = Path(__file__).parents[2]


class ThrottledWriter(DiskWriter):
    """A disk that needs 0.1 s per frame file."""

    def _store(self, path: Path, data: bytes) -> None:
        time.sleep(0.1)
        super()._store(path, data)


class FullDisk(DiskWriter):
    """A disk with ``space`` bytes left: writes beyond it fail with ENOSPC after writing what fits."""

    space = 0

    def _write(self, fd: int, data: bytes) -> int:
        if len(data) > self.space:
            os.write(fd, data[:self.space])  # a partial line reaches the file, as on a real full disk
            self.space = 0
            raise OSError(errno.ENOSPC, "No space left on device")
        self.space -= len(data)
        return os.write(fd, data)

    def _store(self, path: Path, data: bytes) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")


async def test_a_slow_disk_drops_frames_but_never_slows_processing(tmp_path, monkeypatch):
    monkeypatch.setattr(recorder_module, "DiskWriter", functools.partial(ThrottledWriter, max_image_bytes=8 * MB))
    config = with_overrides(Config(), source="synthetic:?fps=30", runs_dir=str(tmp_path), record_video=False,
                            processor="tests.recording.recorder_processors:SaveEveryFrame",  # JPEGs: drops match rows
                            save_max_hz=0)  # every frame's save reaches the disk
    core = UavCore(config)
    await core.start()
    await asyncio.sleep(2.5)
    stats, status = core.worker.stats, core.status().recording
    await core.stop()

    # The processor kept up with the camera although the disk takes 0.1 s per frame (30 frames/s saved).
    assert stats.frames_processed >= 45
    assert stats.frames_skipped <= 0.15 * stats.frames_processed
    assert status["drops"]["queue_full"] > 0.3 * stats.frames_processed
    warnings = [e for e in core.events.recent if e.kind == "recorder"]
    assert len(warnings) == 1 and "cannot keep up" in warnings[0].message

    run = dataset.load(core.recorder.run_dir)
    frames = run.frames
    assert frames["frame_id"].tolist() == list(range(1, len(frames) + 1))
    assert frames["n"].tolist() == list(range(1, len(frames) + 1))  # extras are kept when the image is dropped
    saved = frames[frames["saved"]]
    assert len(saved) == core.recorder.writer.images_written > 5
    assert (~frames["saved"]).sum() == core.recorder.writer.dropped["queue_full"]
    for name in saved["image"]:
        assert cv2.imread(str(run.path / name)) is not None
    assert not list(run.path.rglob("*.tmp")) and not (run.path / ".pending").exists()


def test_a_full_disk_keeps_whole_lines_and_reports_once(tmp_path):
    problems = []
    writer = FullDisk(tmp_path, {"t": ["i", "text"]}, flush_s=0.02, on_problem=lambda *p: problems.append(p))
    writer.space = 2000
    writer.start()
    for i in range(200):
        assert writer.put(Row("t", [i, f"row {i} " + "x" * 20]))
        if i % 20 == 0:
            time.sleep(0.05)
    assert writer.put_image("frames/1.jpg", np.zeros((8, 8, 3), np.uint8))  # queued; the disk refuses it
    writer.close()

    text = (tmp_path / "t.csv").read_text()
    assert text.endswith("\n")
    table = pd.read_csv(tmp_path / "t.csv")
    assert 20 <= len(table) < 200
    assert table["i"].tolist() == list(range(len(table)))
    assert writer.dropped["disk_full"] == 200 - len(table) + 1  # the rows that did not fit, and the frame
    assert writer.rows_written["t"] == len(table)
    assert [p[0] for p in problems] == ["disk_full"]
    assert not list(tmp_path.rglob("*.tmp")) and not list(tmp_path.rglob("*.jpg"))


def test_the_size_cap_stops_frames_and_rows(tmp_path):
    writer = DiskWriter(tmp_path, {"t": ["i"]}, max_disk_bytes=20_000)
    writer.start()
    image = np.random.default_rng(0).integers(0, 255, (240, 320, 3), np.uint8)  # ~60 kB as JPEG
    assert writer.put_image("frames/a.jpg", image)
    deadline = time.monotonic() + 5
    while writer.images_written < 1 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert not writer.put_image("frames/b.jpg", image)
    assert writer.image_refused() == "disk_cap"
    writer.put(Row("t", [1]))
    writer.close()
    assert (tmp_path / "frames/a.jpg").is_file() and not (tmp_path / "frames/b.jpg").exists()
    assert not (tmp_path / "t.csv").exists()
    assert writer.dropped == {"disk_cap": 2}


def test_the_disk_guards_cover_the_csv_files(tmp_path):
    """Rows alone (a processor's huge strings, say) stop at max_disk_mb, and at min_free_mb."""
    problems: list[str] = []
    writer = DiskWriter(tmp_path / "capped", {"t": ["text"]}, max_disk_bytes=100_000, flush_s=0.01,
                        on_problem=lambda reason, message: problems.append(reason))
    (tmp_path / "capped").mkdir()
    writer.start()
    for _ in range(200):  # 2 MB offered, 10 kB a row
        writer.put(Row("t", ["x" * 10_000]))
        time.sleep(0.001)
    writer.close()
    size = (tmp_path / "capped" / "t.csv").stat().st_size
    assert 100_000 <= size < 100_000 + 10 * 10_001  # stops within the batch that crossed the cap
    assert writer.dropped["disk_cap"] > 100 and problems == ["disk_cap"]

    floor = DiskWriter(tmp_path, {"t": ["i"]}, min_free_bytes=2**62)  # more than any disk has free
    floor.start()
    floor.put(Row("t", [1]))
    floor.close()
    assert not (tmp_path / "t.csv").exists() and floor.dropped == {"min_free": 1}


def test_sigkill_leaves_csv_that_parses_up_to_the_last_flush(tmp_path):
    runs = tmp_path / "runs"
    process = subprocess.Popen(
        [sys.executable, "-m", "uav_tui", "--no-ui", "--duration", "60", "--runs-dir", str(runs), "--record-every",
         "1", "--source", "synthetic:?fps=30"],
        env={**os.environ, "PYTHONPATH": str(REPO)}, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            frames_csv = next(runs.glob("*/frames.csv"), None) if runs.exists() else None
            if frames_csv is not None and frames_csv.read_bytes().count(b"\n") > 40:
                break
            assert process.poll() is None, process.stderr.read().decode()
            time.sleep(0.1)
        else:
            raise AssertionError("no frames recorded within 30 s")
        time.sleep(0.3)
        process.send_signal(signal.SIGKILL)
        process.wait(10)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
        process.stderr.close()

    run_dir = frames_csv.parent
    for name in ("frames.csv", "events.csv"):
        data = (run_dir / name).read_bytes()
        assert data.endswith(b"\n"), f"{name} ends with a partial line"
    run = dataset.load(run_dir)
    assert len(run.frames) >= 40
    assert run.frames["frame_id"].tolist() == list(range(1, len(run.frames) + 1))
    for name in run.frames["image"].dropna():  # a frame file is complete or absent
        path = run_dir / name
        assert not path.exists() or cv2.imread(str(path)) is not None
    assert "end_wall_ns" not in run.info
    [listed] = list_runs(runs)
    assert listed["finished"] is False and listed["frames"] == len(run.frames)
