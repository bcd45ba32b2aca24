"""A recorded ``position_hold`` flight replayed at ``--speed max`` gives the same processor outputs frame by frame,
also while another process loads every core, and in a platform thread as in its own process: position_hold paces
its estimates by the frame's clock (``tmMgr.snapshot().frame_t_ns``), not by this computer's, and reads the
telemetry at the frame's capture, whichever host runs it."""

from __future__ import annotations

import asyncio
import subprocess
import sys
from pathlib import Path

import pandas as pd

from tests.core.flight_helpers import flying_core, wait_until
from uav_tui.config import load_config
from uav_tui.recorded import dataset
from uav_tui.replay.runner import ReplayJob, replay_run

OUTPUTS = ["t_mono_ns", "vx", "vy", "vt", "box_x", "hold_forward_m", "hold_right_m", "hold_inliers", "saved"]
"""What the processor said about each frame (its vector, its saved fields) and which frame that was."""


async def _fly(tmp_path: Path) -> Path:
    async with flying_core(tmp_path, altitude=6, processor="position_hold", source="sim:?width=320&height=240",
                           record=True, runs_dir=str(tmp_path / "runs"), save_max_hz=0) as core:
        await core.execute("f 1")  # store the reference view: hold here
        await core.execute("vector 0.8 -0.8 2")  # pushed away: the estimates change frame by frame
        await wait_until(lambda: not core.controller.vector_active, 5, "the push to end")
        await core.execute("autonomy on")
        await asyncio.sleep(3.0)
        run_dir = core.recorder.run_dir
    return run_dir


def _replay(run: Path, out: Path, isolation: str = "process") -> pd.DataFrame:
    config = load_config(None, {"processor": "position_hold", "runs_dir": str(out), "save_max_hz": 0,
                                "isolation": isolation})
    result = replay_run(ReplayJob(str(run), config, "max"))
    frames = dataset.load(result.replay).frames
    return frames[OUTPUTS].reset_index(drop=True)


def test_a_position_hold_replay_gives_the_same_outputs_under_load_and_in_either_host(tmp_path: Path) -> None:
    flight = asyncio.run(_fly(tmp_path))
    quiet = _replay(flight, tmp_path / "quiet")
    hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2)]  # both cores busy
    try:
        loaded = _replay(flight, tmp_path / "loaded")
    finally:
        for hog in hogs:
            hog.kill()
            hog.wait()
    estimates = quiet["hold_forward_m"].notna()
    assert len(quiet) > 100 and 10 < estimates.sum() < len(quiet) / 2  # 5 estimates a second of a 30 FPS camera
    assert quiet["vx"].notna().sum() == estimates.sum() and (quiet["vx"].abs() > 0.05).any()
    pd.testing.assert_frame_equal(quiet, loaded)
    pd.testing.assert_frame_equal(quiet, _replay(flight, tmp_path / "thread", "thread"))
