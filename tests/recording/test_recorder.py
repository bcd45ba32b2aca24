"""The recorder inside a running core (no flight controller): ids, raw frames, snapshots, run.json."""

from __future__ import annotations

import asyncio
import json

import pandas as pd
import pytest

from uav_tui.config import Config, with_overrides
from uav_tui.core import UavCore
from uav_tui.errors import UavError
from uav_tui.recorded import dataset
from uav_tui.recording import image_name


def _config(tmp_path, **changes):
    return with_overrides(Config(), source="synthetic:?fps=30", runs_dir=str(tmp_path / "runs"), **changes)


async def _frames_after(core: UavCore, count: int, timeout: float = 10.0) -> None:
    target = core.worker.stats.frames_processed + count
    async with asyncio.timeout(timeout):
        while core.worker.stats.frames_processed < target:
            await asyncio.sleep(0.02)


async def test_ids_stay_unique_across_a_camera_switch_and_every_nth_frame_is_saved(tmp_path):
    core = UavCore(_config(tmp_path, record_every=4))
    await core.start()
    await _frames_after(core, 10)
    await core.execute("source synthetic:?fps=30&seed=3")
    await _frames_after(core, 10)
    snapshot = await core.execute("snapshot")
    status = core.status().recording
    await core.stop()

    run = dataset.load(core.recorder.run_dir)
    frames = run.frames
    assert frames["frame_id"].tolist() == list(range(1, len(frames) + 1))
    assert frames["seq"].diff().min() < 0  # the new camera counted from 1 again; the ids did not
    raw = frames[frames["frame_id"] % 4 == 0]
    assert raw["saved"].all() and raw["image"].tolist() == [image_name(i) for i in raw["frame_id"]]
    snapped = int(snapshot.split()[1])  # "frame 23 saved as .../frames/000023.jpg"
    assert frames.loc[frames["saved"] & (frames["frame_id"] % 4 != 0), "frame_id"].tolist() in ([snapped], [])
    assert frames.set_index("frame_id").loc[snapped, "saved"]
    on_disk = {p.relative_to(run.path).as_posix() for p in (run.path / "frames").glob("*.jpg")}
    assert on_disk == set(frames.loc[frames["saved"], "image"])
    assert status["run_dir"] == str(run.path) and status["frames"] >= 20 and status["dropped"] == 0
    commands = run.events[run.events["kind"] == "command"]["message"].tolist()
    assert "snapshot" in commands and snapshot in commands


async def test_run_json_describes_the_run_and_its_end(tmp_path):
    core = UavCore(_config(tmp_path, processor_args={"save_every": 3}, save_max_hz=0))  # 10 saves a second
    await core.start()
    await _frames_after(core, 9)
    await core.stop()
    info = json.loads((core.recorder.run_dir / "run.json").read_text())
    assert info["config"]["recording"]["runs_dir"] == str(tmp_path / "runs")
    assert info["processor"]["name"] == "processors.template:MeanBrightnessProcessor"
    assert info["source"]["uri"] == "synthetic:?fps=30" and info["source"]["width"] == 640
    assert info["controller"] == {"fc": "none", "description": "none"}
    assert info["end_wall_ns"] > info["start_wall_ns"] and "numpy" in info["versions"]
    assert info["recording"]["frames"] == core.worker.stats.frames_processed
    run = dataset.load(core.recorder.run_dir)
    saved = run.frames[run.frames["saved"]]
    assert len(saved) == len(run.frames) // 3 and saved["brightness"].between(1, 254).all()
    assert run.telemetry.empty and (run.frames["telemetry"] == "none").all()


async def test_save_outside_photo_processing_is_ignored_with_one_warning(tmp_path):
    core = UavCore(_config(tmp_path, processor="tests.recording.recorder_processors:SavesInCatchCmd"))
    await core.start()
    await _frames_after(core, 3)
    await core.execute("roi 10 10 50 50")
    await core.execute("roi 10 10 60 60")
    await core.stop()
    assert core.recorder.misplaced_saves == 2
    warnings = [e.message for e in core.events.recent if e.kind == "recorder"]
    assert len(warnings) == 1 and "outside photo_processing" in warnings[0]
    assert not list((core.recorder.run_dir / "frames").iterdir())


async def test_without_recording_there_is_no_run_and_snapshot_says_why(tmp_path):
    core = UavCore(_config(tmp_path, record=False))
    await core.start()
    try:
        with pytest.raises(UavError, match="recording is off"):
            await core.execute("snapshot")
        assert core.status().recording == {}
    finally:
        await core.stop()
    assert not (tmp_path / "runs").exists()


async def test_an_unwritable_runs_folder_fails_the_start_with_advice(tmp_path):
    (tmp_path / "runs").write_text("a file, not a folder")
    core = UavCore(_config(tmp_path))
    with pytest.raises(UavError, match="--no-record"):
        await core.start()


async def test_the_processors_box_is_recorded_per_frame(tmp_path):
    core = UavCore(_config(tmp_path, processor="tests.recording.recorder_processors:BoxOnEvenFrames"))
    await core.start()
    await _frames_after(core, 8)
    await core.stop()
    run = dataset.load(core.recorder.run_dir)
    frames = run.frames.reset_index(drop=True)
    assert len(frames) >= 8
    for row in frames.itertuples():
        if row.frame_id % 2 == 0:  # frame ids count the processed frames: the processor's count
            assert (row.box_x, row.box_y, row.box_w, row.box_h) == (row.frame_id, 2 * row.frame_id, 10, 20)
        else:
            assert all(pd.isna(v) for v in (row.box_x, row.box_y, row.box_w, row.box_h))
    header, first = (run.path / "frames.csv").read_text().splitlines()[:2]
    columns = dict(zip(header.split(","), first.split(","), strict=False))
    assert [columns[name] for name in ("box_x", "box_y", "box_w", "box_h")] == ["", "", "", ""]


async def test_a_snapshot_of_a_slow_processors_frame_is_marked_saved(tmp_path):
    """A frame's row is written 200 ms after its capture at the latest without telemetry; a processor slower than that
    (a detector on a Pi) had its row written before any ``snapshot`` of it, and the snapshot was on disk unclaimed."""
    core = UavCore(_config(tmp_path, processor="tests.recording.recorder_processors:Slow", fc="none"))
    await core.start()
    await _frames_after(core, 2)
    snapshots = [await core.execute("snapshot") for _ in range(2)]
    await _frames_after(core, 1)
    await core.stop()

    run = dataset.load(core.recorder.run_dir)
    snapped = [int(line.split()[1]) for line in snapshots]
    saved = run.frames.set_index("frame_id").loc[snapped]
    assert saved["saved"].all() and saved["image"].tolist() == [image_name(i) for i in snapped]
    on_disk = {p.relative_to(run.path).as_posix() for p in (run.path / "frames").glob("*.jpg")}
    assert on_disk == set(run.frames.loc[run.frames["saved"], "image"])
