"""A recorded flight in the simulator: rows, files and interpolated positions against ground truth."""

from __future__ import annotations

import asyncio
import threading
import time

import cv2
import numpy as np

from uav_tui.config import Config, with_overrides
from uav_tui.core import UavCore
from uav_tui.errors import ControllerError
from uav_tui.recorded import dataset
from uav_tui.recording import image_name

LATE_BY_AT_MOST_S = 1.0
"""How long before its stamp the instant whose truth a telemetry row holds is looked for. Rows are stamped when the loop
receives them (docs/recording-and-replay.md): a few ms on a quiet machine, more when the loop is kept waiting, so the
frames' positions lag the truth by speed x that delay (p95 0.142 m at load 3-12 against 0.008-0.017 m quiet). This
test checks what the recording decides, which no load changes: every row is the truth of a recent instant, and
every frame's position is what the rows around its capture give."""

TRUTH_M = 0.02
"""A row's position against the simulator's truth at the instant it matches best (truth sampled at 50 Hz): 0.001 m
p95 measured, quiet and beside two busy loops."""

BETWEEN_ROWS_M = 0.03
"""A frame's position against a line between the rows around its capture (p95). Measured 0.010 m (the rows of a
vehicle at rest are held, not drawn as a line: see ``STATIC_NS``); a frame given a neighbouring row's position
instead (100 ms at the ~1.2 m/s flown here) is 0.12 m off."""


class TruthRecorder:
    """Collects every ground-truth datagram the simulator streams (50 Hz) on a thread."""

    def __init__(self, client) -> None:
        self.client = client
        self.samples: list[dict] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                sample = self.client.wait_latest(0.5)
            except TimeoutError:
                continue
            if "t_mono_ns" in sample and (not self.samples or sample["t_mono_ns"] > self.samples[-1]["t_mono_ns"]):
                self.samples.append(sample)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2)
        self.client.close()

    def at(self, t_mono_ns: np.ndarray, *keys: str) -> np.ndarray:
        """Truth of ``keys`` (default north, east, down) at each instant, linear between the 50 Hz samples."""
        t = np.array([s["t_mono_ns"] for s in self.samples], dtype=np.float64)
        columns = [np.interp(t_mono_ns, t, [s[k] for s in self.samples]) for k in keys or ("n", "e", "d")]
        return columns[0] if len(columns) == 1 else np.stack(columns, axis=1)


def _late_and_off(rows, truth: TruthRecorder) -> tuple[np.ndarray, np.ndarray]:
    """For each telemetry row: how long before its stamp (up to LATE_BY_AT_MOST_S) the truth was nearest to its
    position (s), and how far it was then (m)."""
    lateness = np.arange(0.0, LATE_BY_AT_MOST_S, 0.002)
    stamps = rows["t_mono_ns"].to_numpy(dtype=np.float64)
    position = rows[["north_m", "east_m", "down_m"]].to_numpy(dtype=np.float64)
    late, off = np.empty(len(rows)), np.empty(len(rows))
    for i, (stamp, where) in enumerate(zip(stamps, position, strict=True)):
        distance = np.linalg.norm(truth.at(stamp - lateness * 1e9) - where, axis=1)
        late[i], off[i] = lateness[distance.argmin()], distance.min()
    return late, off


def _between_rows(telemetry, t_mono_ns: np.ndarray) -> np.ndarray:
    """North, east, down at each instant, linear between the rows where each of them changed (as recorded)."""
    columns = []
    for name in ("north_m", "east_m", "down_m"):
        series = telemetry[["t_mono_ns", name]].dropna()
        changed = series[series[name].diff().fillna(1.0) != 0]
        columns.append(np.interp(t_mono_ns, changed["t_mono_ns"].to_numpy(dtype=np.float64), changed[name]))
    return np.stack(columns, axis=1)


async def _wait_for(predicate, timeout: float) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, "the simulated vehicle did not get there in time"
        await asyncio.sleep(0.1)


async def _arm_when_ready(core: UavCore, timeout: float = 20.0) -> None:
    """Arm as soon as the simulator accepts it (it refuses until its GPS has a fix)."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            await core.execute("arm")
            return
        except ControllerError:
            assert time.monotonic() < deadline, "the simulated vehicle never accepted arming"
            await asyncio.sleep(0.5)


async def test_recorded_flight_matches_simulator_truth(tmp_path):
    config = with_overrides(Config(), source="synthetic:?fps=30", fc="sim", runs_dir=str(tmp_path),
                            processor="tests.recording.recorder_processors:SaveEveryFifth", save_max_hz=0)  # 6 a second
    core = UavCore(config)
    await core.start()
    truth = TruthRecorder(core.controller.sim.truth())
    try:
        await _arm_when_ready(core)
        await core.execute("takeoff 3")
        await _wait_for(lambda: (core.telemetry.snapshot().rel_alt_m or 0) > 2.6, 20)
        await core.execute("vector 1 0.6 2")
        await asyncio.sleep(2.2)
        await core.execute("vector -0.8 1 1.5")
        await asyncio.sleep(1.8)
    finally:
        await core.stop("test finished")
        truth.close()
    assert core.recorder is not None
    run = dataset.load(core.recorder.run_dir)
    frames = run.frames

    # Every processed frame has its row, ids are unique, every 5th was saved by the processor.
    assert len(frames) == core.worker.stats.frames_processed
    assert frames["frame_id"].is_unique and frames["frame_id"].is_monotonic_increasing
    saved = frames[frames["saved"]]
    assert len(saved) == len(frames) // 5
    assert (saved["n"] % 5 == 0).all() and saved["label"].tolist() == [f"f{n}" for n in saved["n"].astype(int)]
    assert frames.loc[~frames["saved"], "n"].isna().all()

    # Ids match files, and the files hold the frame as it was when saved (drawn on afterwards).
    files = {p.relative_to(run.path).as_posix() for p in (run.path / "frames").glob("*.jpg")}
    assert files == {image_name(i) for i in saved["frame_id"]} == set(saved["image"])
    first = cv2.imread(str(run.path / saved["image"].iloc[0]))
    assert first[:40, :40].mean() < 240

    # Telemetry: one row per update, and the frames' positions match the simulator's ground truth.
    assert len(run.telemetry) == core.telemetry.updates > 0
    flying = frames[(frames["telemetry"] == "interpolated") & frames["in_air"].fillna(False)]
    assert len(flying) > 0.5 * len(frames)
    recorded = flying[["north_m", "east_m", "down_m"]].to_numpy(dtype=np.float64)
    expected = truth.at(flying["t_mono_ns"].to_numpy(dtype=np.float64))
    travelled = np.ptp(expected[:, :2], axis=0).max()
    assert travelled > 1.5, "the vehicle must have moved for the comparison to mean anything"
    # In the air and with a position (under load, in_air can arrive before the first position)
    rows = run.telemetry[run.telemetry["in_air"].fillna(False)].dropna(subset=["north_m", "east_m", "down_m"])
    late_s, off_m = _late_and_off(rows, truth)
    assert np.percentile(off_m, 95) < TRUTH_M, f"p95 {np.percentile(off_m, 95):.3f} m off the truth of the last " \
        f"{LATE_BY_AT_MOST_S} s (best matched {np.median(late_s):.3f} s before the stamp, median)"
    between = _between_rows(run.telemetry, flying["t_mono_ns"].to_numpy(dtype=np.float64))
    assert np.percentile(np.linalg.norm(recorded - between, axis=1), 95) < BETWEEN_ROWS_M
    # Attitude: 10 Hz samples of a vehicle that tilts by 15-20 degrees within a tick when a vector starts;
    # between such steps the interpolation follows the truth closely.
    for name in ("roll", "pitch"):
        truth_deg = truth.at(flying["t_mono_ns"].to_numpy(dtype=np.float64), name)
        assert np.median(np.abs(flying[f"{name}_deg"].to_numpy(dtype=np.float64) - truth_deg)) < 0.2
    # Discrete fields (1-2 Hz from the autopilot) come from the nearest sample.
    assert "OFFBOARD" in set(flying["flight_mode"].dropna()) and flying["armed"].iloc[-1]
    assert not run.events[run.events["kind"] == "command"].empty

