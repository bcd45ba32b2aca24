"""A run locked on one of the ``sim:`` camera's cars on the built-in vehicle, recorded: each frame's row says which
track the lock was on and its state, and a replay gives the lock the operator's ``lock``/``unlock`` before the same
frames, so it flies the same vectors (issue 50)."""

from __future__ import annotations

import asyncio
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tests.core.flight_helpers import RENDERER_STALL_S, flying_core, wait_until, what_happened
from uav_tui.config import load_config
from uav_tui.flight.track_lock import LockState
from uav_tui.recorded import dataset
from uav_tui.replay.runner import ReplayJob, replay_run

SOURCE = "sim:?width=320&height=240&fps=15&targets=3&target_speed=0.5"
"""Three cars on rings of 6, 12 and 18 m round home at 0.5 m/s, seen by the down camera."""
RED_CARS = "tests.recording.recorder_processors:RedCars"
"""Reports each red blob as a ``car`` and has no vector of its own: only the lock makes one."""


async def _fly(tmp_path: Path) -> tuple[Path, int]:
    async with flying_core(tmp_path, altitude=25.0, climb_ms=5.0, source=SOURCE, processor=RED_CARS, record=True,
                           runs_dir=str(tmp_path / "runs"), camera_stall=RENDERER_STALL_S) as core:
        await wait_until(lambda: core.lock.newest and core.lock.newest[0].track_id is not None, 10, "a track")
        await asyncio.sleep(1.0)  # unlocked frames first
        track = core.lock.newest[0].track_id
        assert track is not None
        await core.execute(f"lock {track}")
        await core.execute("autonomy on")
        await wait_until(lambda: core.gate.executed >= 30, 15, f"the lock's vectors flown; {what_happened(core)}")
        assert core.lock.state is LockState.LOCKED, what_happened(core)
        await core.execute("unlock")
        await asyncio.sleep(1.0)
        await core.execute("autonomy off")
        run_dir = core.recorder.run_dir  # type: ignore[union-attr]
    return run_dir, track


@pytest.fixture(scope="module")
def locked_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, int]:
    """A recorded run: unlocked frames, then locked on the first car's track under autonomy, then unlocked."""
    return asyncio.run(_fly(tmp_path_factory.mktemp("locked")))


def test_each_frame_says_which_track_the_lock_was_on(locked_run: tuple[Path, int]) -> None:
    run_dir, track = locked_run
    run = dataset.load(run_dir)
    frames = run.frames
    on = frames["lock_track"].notna()
    # One stretch of locked frames, with unlocked ones before and after it.
    assert on.any() and not on.iloc[0] and not on.iloc[-1]
    assert (on.astype(int).diff().abs().fillna(0).sum()) == 2
    assert (frames.loc[on, "lock_track"] == track).all()  # the car never left the picture: never renumbered
    assert set(frames.loc[on, "lock_state"]) <= {"locked", "lost"}
    assert (frames.loc[on, "lock_state"] == "locked").mean() > 0.9
    assert (frames.loc[~on, "lock_state"].fillna("") == "").all()
    # While locked, the frame's box is the locked track's (detections.csv) and its vector the lock's: the
    # processor has none.
    seen = frames[on & (frames["lock_state"] == "locked")].merge(
        run.detections[run.detections["track_id"] == track], on="frame_id", suffixes=("", "_track"))
    assert len(seen) == (on & (frames["lock_state"] == "locked")).sum()
    for side in ("x", "y", "w", "h"):
        assert seen[f"box_{side}"].equals(seen[f"box_{side}_track"].rename(f"box_{side}"))
    assert frames.loc[on, "vx"].notna().mean() > 0.9 and frames.loc[~on, "vx"].isna().all()
    executed = frames["decision"].fillna("").str.startswith("executed")
    assert executed.sum() >= 30 and on[executed].all()
    assert isinstance(frames["lock_track"].dtype, pd.Int64Dtype)


def test_a_replay_locks_and_unlocks_before_the_same_frames_and_flies_the_same_vectors(
        locked_run: tuple[Path, int], tmp_path: Path) -> None:
    run_dir, track = locked_run
    config = load_config(None, {"processor": RED_CARS, "runs_dir": str(tmp_path)})
    replayed = dataset.load(replay_run(ReplayJob(str(run_dir), config, "max")).replay)
    events = replayed.events[replayed.events["origin"] == "replay"]
    assert events["message"].tolist()[:2] == [f"lock {track}", f"locked on track #{track} (car)"]
    assert "unlock" in events["message"].tolist()
    joined = dataset.compare(run_dir, replayed)
    assert len(joined) >= 0.9 * len(replayed.frames)
    # Locked on the same frames, in the same state; the lock's vectors from the same boxes (up to the video's
    # compression) and judged alike: the processor has no vector of its own, so without the lock none would fly.
    assert joined["lock_track_a"].equals(joined["lock_track_b"].rename("lock_track_a"))
    assert (joined["lock_state_a"].fillna("") == joined["lock_state_b"].fillna("")).all()
    on = joined["lock_track_a"].notna()
    assert on.sum() >= 30
    for axis in ("vx", "vy", "vt"):
        a, b = joined[f"{axis}_a"].to_numpy(np.float64), joined[f"{axis}_b"].to_numpy(np.float64)
        assert np.allclose(a, b, atol=0.05, equal_nan=True), axis
    executed_a = joined["decision_a"].fillna("").str.startswith("executed")
    executed_b = joined["decision_b"].fillna("").str.startswith("executed")
    assert executed_b.sum() >= 30 and (executed_a == executed_b).mean() > 0.97
