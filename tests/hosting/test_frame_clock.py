"""The frame's clock in ``tmMgr.snapshot()`` and the ``tmMgr.save`` rate, through the real platform in both
isolations; the telemetry "at the frame's capture" that every host gives."""

from __future__ import annotations

import asyncio

import numpy as np
import pytest

from controllers.base import Telemetry
from uav_tui.config import Config, with_overrides
from uav_tui.core import UavCore
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.headless import format_status
from uav_tui.recorded import dataset

CLOCK = "tests.recording.recorder_processors:FrameClock"
EVERY_FRAME = "tests.recording.recorder_processors:SaveEveryFrame"


async def _record(tmp_path, processor: str, isolation: str, seconds: float, **changes) -> dataset.Dataset:
    config = with_overrides(Config(), source="synthetic:?fps=30&width=160&height=120", runs_dir=str(tmp_path),
                            processor=processor, isolation=isolation, record_video=False, **changes)
    core = UavCore(config)
    await core.start()
    try:
        await asyncio.sleep(seconds)
    finally:
        await core.stop()
    return dataset.load(core.recorder.run_dir)


@pytest.mark.parametrize("isolation", ["thread", "process"])
async def test_the_processor_sees_each_frames_number_and_capture_time(tmp_path, isolation: str) -> None:
    run = await _record(tmp_path, CLOCK, isolation, 1.5, save_max_hz=0)
    frames = run.frames.dropna(subset=["clock_seq"])
    assert len(frames) >= 20 and len(frames) == len(run.frames)
    assert frames["clock_seq"].astype("int64").tolist() == frames["seq"].tolist()
    assert frames["clock_t_ns"].astype("int64").tolist() == frames["t_mono_ns"].tolist()
    assert frames["clock_wall_ns"].astype("int64").tolist() == frames["t_wall_ns"].tolist()


@pytest.mark.parametrize("isolation", ["thread", "process"])
async def test_saves_above_the_rate_are_dropped_by_frame_time(tmp_path, isolation: str) -> None:
    run = await _record(tmp_path, EVERY_FRAME, isolation, 3.0, save_max_hz=2)
    frames = run.frames
    seconds = (frames["t_mono_ns"].iloc[-1] - frames["t_mono_ns"].iloc[0]) / 1e9
    saved = frames[frames["saved"]]
    assert len(frames) >= 45 and seconds >= 1.5
    assert 2 * seconds - 1 <= len(saved) <= 2 + 2 * seconds + 1  # a burst of 2, then 2 a second
    # A token bucket (burst 2, 2 a second): any n saves in a row span at least (n - 2) / 2 s of frame time. Not
    # "every gap >= 0.4 s": after a long gap (frames late under load) the next may come sooner (0.63 s, 0.37 s).
    times = saved["t_mono_ns"].to_numpy(dtype=np.float64) / 1e9
    for first in range(len(times)):
        for last in range(first + 1, len(times)):
            assert last - first + 1 <= 2 + 2 * (times[last] - times[first]) + 1e-6, times.tolist()


@pytest.mark.parametrize("isolation", ["thread", "process"])
async def test_saves_dropped_are_counted_in_the_status_and_the_headless_line(tmp_path, isolation: str) -> None:
    config = with_overrides(Config(), source="synthetic:?fps=30&width=160&height=120", runs_dir=str(tmp_path),
                            processor=EVERY_FRAME, isolation=isolation, record_video=False, save_max_hz=2)
    core = UavCore(config)
    await core.start()
    try:
        await asyncio.sleep(2.0)
        status = core.status()
        stored = status.recording["frames_saved"]
    finally:
        await core.stop()
    # Before: dropped without a word after the first warning; in a process of its own, not counted at all.
    throttled = status.saves_dropped["throttled"]
    assert throttled >= 20 and stored <= 2 + 2 * 2.0 + 1
    assert throttled + stored >= status.pipeline.frames_processed - 2  # every frame saved once: stored or dropped
    assert f" | {throttled} saves dropped ({throttled} throttled) | " in format_status(status, 2.0)
    assert status.as_dict()["saves_dropped"] == {"throttled": throttled}


def test_the_telemetry_at_a_capture_is_the_newest_update_received_by_then() -> None:
    telemetry = TelemetryManager(None)
    assert telemetry.at(5)[0] == Telemetry()  # nothing received yet
    for t_ns, altitude in ((100, 1.0), (200, 2.0), (300, 3.0)):
        telemetry.apply({"t_mono_ns": t_ns, "t_wall_ns": t_ns, "rel_alt_m": altitude})
    assert telemetry.at(99)[0] == Telemetry()  # captured before the first update
    assert [telemetry.at(t)[0].rel_alt_m for t in (100, 150, 299, 300, 10**12)] == [1.0, 1.0, 2.0, 3.0, 3.0]
