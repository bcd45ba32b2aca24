"""dataset.load reads back exactly what the recorder wrote, with proper dtypes and a time index."""

from __future__ import annotations

import time

import numpy as np
import pandas as pd
import pytest

from tests.recording.recorder_fakes import FakeCore
from uav_tui.config import RecordingConfig
from uav_tui.errors import UavError
from uav_tui.recorded import dataset
from uav_tui.recording import Recorder


def _record_run(tmp_path):
    core = FakeCore()
    recorder = Recorder.open(RecordingConfig(runs_dir=str(tmp_path)), {"processor": {"name": "test"}},
                             telemetry_expected=True)
    core.attach(recorder)
    core.telemetry.apply({"north_m": 0.0, "yaw_deg": 179.0, "lat_deg": 47.397742, "armed": False,
                          "flight_mode": "HOLD", "fc_boot_ms": 1_000, "satellites": 10, "battery_v": 16.1})
    time.sleep(0.01)
    image = np.full((48, 64, 3), 90, np.uint8)

    def saves(result):
        core.telemetry.save(image, score=0.5, label='a, "b"', hits=3, ok=True, box=[1, 2, 3, 4])
        result.vector, result.decision = (0.5, -0.25, 1.0), "executed"

    def fails(result):
        result.error, result.decision = "Traceback (most recent call last):\nValueError: bad frame", "no vector"

    first = core.process(image, 1, saves)
    time.sleep(0.005)
    second = core.process(image, 2, fails)
    time.sleep(0.31)  # the fields the next sample does not change count as constant (not held past their value)
    core.telemetry.apply({"north_m": 2.0, "yaw_deg": -179.0, "armed": True, "flight_mode": "OFFBOARD"})
    core.events.emit("warning", "autonomy", "vector rejected: vx is nan,\nsecond line", "tui")
    recorder.close()
    return recorder, [first.frame, second.frame]


def test_load_round_trips_values_and_dtypes(tmp_path):
    recorder, captured = _record_run(tmp_path)
    run = dataset.load(recorder.run_dir)

    frames = run.frames
    assert frames["frame_id"].tolist() == [1, 2]
    assert frames["t_mono_ns"].tolist() == [f.t_mono_ns for f in captured]  # nanoseconds survive exactly
    assert frames["t_wall_ns"].tolist() == [f.t_wall_ns for f in captured]
    assert list(frames.index) == [pd.Timestamp(f.t_wall_ns, unit="ns", tz="UTC") for f in captured]
    assert frames.index.name == "time" and frames["t_s"].between(0, 5).all()
    expected = {"frame_id": "Int64", "t_mono_ns": "Int64", "t_vector_ns": "Int64", "vx": "float64",
                "decision": "string", "saved": "boolean", "armed": "boolean", "north_m": "float64",
                "yaw_deg": "float64", "fc_boot_ms": "Int64", "satellites": "Int64", "flight_mode": "string",
                "score": "float64", "label": "string", "hits": "Int64", "ok": "boolean", "box": "object"}
    assert {name: str(frames[name].dtype) for name in expected} == expected
    first, second = frames.iloc[0], frames.iloc[1]
    assert (first["vx"], first["vy"], first["vt"], first["decision"]) == (0.5, -0.25, 1.0, "executed")
    assert (first["score"], first["label"], first["hits"], first["ok"], first["box"]) == (0.5, 'a, "b"', 3, True,
                                                                                          [1, 2, 3, 4])
    assert first["saved"] and (run.path / first["image"]).is_file() and pd.isna(second["image"])
    assert pd.isna(second["vx"]) and second["error"] == "ValueError: bad frame" and pd.isna(second["score"])
    assert run.extra_columns == ["score", "label", "hits", "ok", "box"]
    # Interpolated between the two telemetry samples: north inside (0, 2), yaw across +-180 the short way.
    assert frames["telemetry"].tolist() == ["interpolated"] * 2
    assert ((frames["north_m"] > 0) & (frames["north_m"] < 2)).all() and frames["north_m"].is_monotonic_increasing
    assert ((frames["yaw_deg"].abs() > 179) & (frames["yaw_deg"].abs() <= 180)).all()
    assert frames["lat_deg"].tolist() == [47.397742] * 2 and frames["fc_boot_ms"].tolist() == [1_000] * 2

    telemetry = run.telemetry
    assert len(telemetry) == 2 and str(telemetry["armed"].dtype) == "boolean"
    assert telemetry["armed"].tolist() == [False, True] and telemetry["in_air"].isna().all()
    assert telemetry["flight_mode"].tolist() == ["HOLD", "OFFBOARD"] and telemetry["battery_v"].tolist() == [16.1] * 2

    events = run.events
    # control characters are escaped on the way to the file: a line break reads as \n (the event log
    # indented the second line: no outside text starts a line of its own)
    assert events["message"].tolist() == ["vector rejected: vx is nan,\\n  second line"]
    assert (events["level"].iloc[0], events["kind"].iloc[0], events["origin"].iloc[0]) == ("warning", "autonomy", "tui")
    assert run.info["processor"] == {"name": "test"} and run.info["end_wall_ns"] > run.info["start_wall_ns"]


def test_load_refuses_a_folder_that_is_not_a_run(tmp_path):
    with pytest.raises(UavError, match="not a recorded run"):
        dataset.load(tmp_path)


def test_load_lists_the_frames_whose_telemetry_is_extrapolated_and_by_how_much(tmp_path):
    core = FakeCore()
    recorder = Recorder.open(RecordingConfig(runs_dir=str(tmp_path)), {}, telemetry_expected=True)
    core.attach(recorder)
    core.telemetry.apply({"north_m": 0.0, "roll_deg": 1.0})
    core.telemetry.apply({"north_m": 1.0, "roll_deg": 1.0})
    image = np.zeros((8, 8, 3), np.uint8)
    core.process(image, 1, lambda result: None)
    time.sleep(0.02)
    core.telemetry.apply({"north_m": 2.0, "roll_deg": 2.0})  # brackets frame 1
    time.sleep(0.02)
    core.process(image, 2, lambda result: None)  # the vehicle's link stops after this: nothing brackets frame 2
    recorder.close()
    run = dataset.load(recorder.run_dir)
    assert run.frames["telemetry"].tolist() == ["interpolated", "held"]
    assert run.extrapolated["frame_id"].tolist() == [2]
    gap_ms = (run.frames["t_mono_ns"].iloc[1] - run.telemetry["t_mono_ns"].iloc[-1]) / 1e6
    assert run.extrapolated["extrapolated_ms"].iloc[0] == pytest.approx(gap_ms, abs=0.1)
