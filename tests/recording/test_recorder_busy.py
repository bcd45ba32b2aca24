"""A flight recorded while the telemetry comes late (a busy computer): every frame still carries the telemetry of its
capture, and so do its geo-located positions and its replay."""

from __future__ import annotations

import asyncio
import contextlib
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from controllers.base import Telemetry
from controllers.replay import read_telemetry
from tests.core.flight_helpers import flying_core
from uav_tui.config import load_config
from uav_tui.flight.geolocate import locate_row
from uav_tui.recorded import dataset
from uav_tui.recording.interpolate import CONTINUOUS, DISCRETE, FIELDS, TelemetryHistory
from uav_tui.recording.located import GEO_COLUMNS, geo_cells
from uav_tui.replay.runner import ReplayJob, replay_run

PROCESSOR = "tests.recording.recorder_processors:FixedBox"
SOURCE = "sim:?width=160&height=120&fps=15"
PAUSE_S = 0.9
"""How long telemetry is held back at a time: longer than a frame row used to wait for the telemetry after its
capture (0.5 s)."""


class Bursts:
    """Wraps a telemetry input: calls wait while :meth:`held`, then are made at once, in order."""

    def __init__(self, function) -> None:
        self.function, self.waiting, self.paused = function, [], False

    def __call__(self, update):
        if self.paused:
            self.waiting.append(update)
            return None
        return self.function(update)

    @contextlib.asynccontextmanager
    async def held(self):
        self.paused = True
        try:
            yield
        finally:
            self.paused = False
            for update in self.waiting:
                self.function(update)
            self.waiting.clear()


def _delay(core, where: str) -> Bursts:
    """``platform``: the vehicle's telemetry reaches the platform in bursts, as from a starved ``mavsdk_server`` on a
    busy computer (stamped when it arrives, while frames keep coming). ``recorder``: the recorder gets each sample
    late, with its stamp (the writer behind the loop)."""
    if where == "platform":
        bursts = core.telemetry.apply = Bursts(core.telemetry.apply)
        return bursts
    listeners = core.telemetry._listeners
    index = listeners.index(core.recorder.on_telemetry)
    bursts = listeners[index] = Bursts(listeners[index])
    return bursts


async def _fly_in_bursts(tmp_path: Path, where: str) -> tuple[Path, object]:
    async with flying_core(tmp_path, source=SOURCE, processor=PROCESSOR, record=True, runs_dir=str(tmp_path / "runs"),
                           save_max_hz=0) as core:
        bursts = _delay(core, where)
        for vector in ("vector 1.2 0.6 1.5", "vector -1.0 1.0 1.5"):
            async with bursts.held():  # the vehicle tilts and speeds up meanwhile
                await core.execute(vector)
                await asyncio.sleep(PAUSE_S)
            await asyncio.sleep(0.4)
            async with bursts.held():  # and stops
                await asyncio.sleep(PAUSE_S)
            await asyncio.sleep(0.6)
        camera = core.camera
        run_dir = core.recorder.run_dir
    return run_dir, camera


@pytest.fixture(scope="module", params=["platform", "recorder"])
def held_up(request, tmp_path_factory) -> tuple[Path, object]:
    """A recorded flight (two vectors, telemetry held back as each starts and ends), and its camera model."""
    return asyncio.run(_fly_in_bursts(tmp_path_factory.mktemp("held_up"), request.param))


def _expected(run_dir: Path, frames: pd.DataFrame) -> pd.DataFrame:
    """The telemetry columns of each frame whose capture the telemetry brackets (each field has a sample before and
    one after it), interpolated from the run's whole telemetry.csv."""
    rows = read_telemetry(run_dir / "telemetry.csv")
    history = TelemetryHistory(keep_ns=1 << 62)
    for row in rows:
        history.add(Telemetry(**row), row["t_mono_ns"])
    first = max(next(row["t_mono_ns"] for row in rows if row.get(name) is not None)
                for name in CONTINUOUS if any(row.get(name) is not None for row in rows))
    rows = {int(t): history.at(int(t))[0] for t in frames["t_mono_ns"] if t >= first and history.covers(int(t))}
    return pd.DataFrame.from_dict(rows, orient="index", columns=list(FIELDS))


def _assert_same_telemetry(frames: pd.DataFrame, expected: pd.DataFrame) -> None:
    got = frames.set_index("t_mono_ns").loc[expected.index]
    for name in CONTINUOUS:
        a, b = got[name].to_numpy(np.float64), expected[name].to_numpy(np.float64)
        wrong = ~np.isclose(a, b, atol=1e-6, rtol=0, equal_nan=True)
        assert not wrong.any(), f"{name}: {wrong.sum()} of {len(a)} frames differ, by up to {np.nanmax(abs(a - b))}"
    for name in DISCRETE:
        assert [None if pd.isna(v) else v for v in got[name]] == [None if pd.isna(v) else v for v in expected[name]], \
            name  # unknown (a first frame before the first GPS report, under load) is None in one, NaN in the other
    assert (got["telemetry"] == "interpolated").all()


def test_telemetry_in_bursts_still_gives_each_frame_the_telemetry_of_its_capture(held_up):
    run_dir, _ = held_up
    run = dataset.load(run_dir)
    expected = _expected(run_dir, run.frames)
    assert len(expected) >= 0.8 * len(run.frames) > 40
    _assert_same_telemetry(run.frames, expected)
    # Only frames the telemetry does not bracket (the last ones, captured after its last sample) are extrapolated.
    bracketed = run.frames["t_mono_ns"].isin(expected.index)
    assert set(run.extrapolated["frame_id"]) <= set(run.frames.loc[~bracketed, "frame_id"])


def test_the_geo_located_box_and_detections_are_those_of_the_interpolated_telemetry(held_up):
    run_dir, camera = held_up
    run = dataset.load(run_dir)
    expected = _expected(run_dir, run.frames)
    frames = run.frames.set_index("t_mono_ns").loc[expected.index]
    detections = run.detections.set_index("t_mono_ns")
    assert (frames["target_status"] == "ok").mean() > 0.9
    for t, values in expected.iterrows():
        frame = frames.loc[t]
        box = tuple(float(frame[name]) for name in ("box_x", "box_y", "box_w", "box_h"))
        for located, where in ((frame, box), (detections.loc[t], (10.0, 10.0, 30.0, 20.0))):
            fresh = geo_cells(locate_row(camera, where, values.to_dict(), at_ns=int(t)))
            recorded = tuple(None if pd.isna(located[name]) else located[name] for name in GEO_COLUMNS)
            assert all(a == b or isinstance(a, float) and math.isclose(a, b, abs_tol=1.5e-8)
                       for a, b in zip(recorded, fresh, strict=True)), (t, recorded, fresh)


def test_its_replay_reproduces_every_frames_telemetry(held_up, tmp_path):
    run_dir, _ = held_up
    config = load_config(None, {"processor": PROCESSOR, "runs_dir": str(tmp_path), "save_max_hz": 0})
    replayed = dataset.load(replay_run(ReplayJob(str(run_dir), config, "max")).replay)
    expected = _expected(run_dir, replayed.frames)
    assert len(expected) >= 0.8 * len(replayed.frames)
    _assert_same_telemetry(replayed.frames, expected)
