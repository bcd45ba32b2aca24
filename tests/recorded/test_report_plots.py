"""What the report's plots show: each extra field on its own scale, executed vectors as a few arrows on metre
axes, the tracked box over time, commanded vs actual velocity with autonomy spans, a processing rate without a
start-up spike, and one self-contained report.html."""

from __future__ import annotations

import base64
import math
import re
import time

import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import LineCollection
from matplotlib.patches import Rectangle
from matplotlib.quiver import Quiver

from tests.recording.recorder_fakes import FakeCore
from uav_tui.config import RecordingConfig
from uav_tui.recorded import dataset, report
from uav_tui.recorded.report import PLOTS, autonomy_spans, draw, processing_rate, write_report
from uav_tui.recording import Recorder
from uav_values.camera import CameraModel
from uav_values.detections import Detected


def _frame(core: FakeCore, i: int, result) -> None:
    core.telemetry.save(result.frame.image, offset_m=0.001 * (i % 3), inliers=240 + i)
    result.vector = (0.6, -0.2, 0.5) if i % 5 == 0 else None
    result.decision = "executed" if result.vector else "no vector"
    result.box = (10 + i, 20, 30, 40) if i < 30 else None  # tracked, then lost


@pytest.fixture
def hover_run(tmp_path):
    """A vehicle hovering in place (millimetre noise), heading east, autonomy on in the middle of the run;
    max_speed 0.5 m/s."""
    core = FakeCore()
    info = {"processor": {"name": "hover"}, "config": {"safety": {"max_speed": 0.5}},
            "source": {"uri": "rtsp://pilot:secret@192.0.2.1/cam"}}
    recorder = Recorder.open(RecordingConfig(runs_dir=str(tmp_path)), info, telemetry_expected=True)
    core.attach(recorder)
    image = np.zeros((48, 64, 3), np.uint8)
    for i in range(60):
        if i == 15:
            core.events.emit("info", "autonomy", "autonomy ON", "tui")
        if i == 45:
            core.events.emit("info", "autonomy", "autonomy OFF: operator", "tui")
        core.telemetry.apply({"north_m": 3.0 + 0.002 * (i % 2), "east_m": -1.0, "down_m": -5.0, "rel_alt_m": 5.0,
                              "vn_ms": 0.0, "ve_ms": 0.5, "yaw_deg": 90.0, "in_air": True})
        time.sleep(0.004)
        core.process(image, i, lambda result, i=i: _frame(core, i, result))
    recorder.close()
    return recorder.run_dir


def test_each_extra_field_gets_its_own_axis(hover_run):
    axes = draw(dataset.load(hover_run))["extra.png"].axes
    assert [ax.get_ylabel() for ax in axes] == ["offset_m", "inliers"]
    low, high = axes[0].get_ylim()
    assert high - low < 0.01  # millimetres are not flattened by the inliers' scale of ~250


def test_executed_vectors_are_a_few_arrows_the_way_they_flew_and_a_hover_is_drawn_in_metres(hover_run,
                                                                                             monkeypatch):
    monkeypatch.setattr(report, "MAX_ARROWS", 5)
    ax = draw(dataset.load(hover_run))["track.png"].axes[0]
    (arrows,) = (c for c in ax.collections if isinstance(c, Quiver))
    assert arrows.get_label() == "executed vectors (fastest 0.63 m/s), 5 of 12 shown"  # not one ring per frame
    # heading east, 0.6 forward and 0.2 left: 0.6 east and 0.2 north
    assert np.allclose(arrows.U, 0.6) and np.allclose(arrows.V, 0.2)
    for low, high in (ax.get_xlim(), ax.get_ylim()):
        assert high - low == pytest.approx(2.0)  # 2 mm of noise is not stretched over the whole plot
    assert ax.get_xlim()[0] < -1.0 < ax.get_xlim()[1] and ax.get_ylim()[0] < 3.0 < ax.get_ylim()[1]


def test_flight_shows_commanded_and_actual_velocity_and_autonomy_spans(hover_run):
    run = dataset.load(hover_run)
    altitude, _, velocity = draw(run)["flight.png"].axes[:3]
    lines = {line.get_label(): line for line in velocity.get_lines()}
    # heading east at 0.5 m/s north-east frame: forward 0.5, right 0
    assert np.allclose(lines["forward actual"].get_ydata(), 0.5) and np.allclose(lines["right actual"].get_ydata(), 0)
    commanded = {c.get_label(): c for c in velocity.collections if isinstance(c, LineCollection)}
    forward = np.array([segment[0][1] for segment in commanded["forward commanded"].get_segments()])
    right = np.array([segment[0][1] for segment in commanded["right commanded"].get_segments()])
    assert len(forward) == 12 and np.allclose(right, -0.2)
    assert np.allclose(forward, 0.5)  # proposed 0.6, flown as clamped to the run's max_speed
    (start, end), = autonomy_spans(run)
    events = run.events[run.events.kind == "autonomy"].t_s.to_numpy()
    assert (start, end) == (events[0], events[1])
    shaded = [patch for patch in altitude.patches if isinstance(patch, Rectangle)]
    assert len(shaded) == 1 and shaded[0].get_x() == pytest.approx(start)


def test_box_shows_the_tracked_centre_and_size_over_time_with_a_gap_once_lost(hover_run):
    centre, size = draw(dataset.load(hover_run))["box.png"].axes
    x, y = (line.get_ydata() for line in centre.get_lines())
    width, height = (line.get_ydata() for line in size.get_lines())
    assert np.allclose(x[:30], 25 + np.arange(30)) and np.allclose(y[:30], 40)
    assert np.allclose(width[:30], 30) and np.allclose(height[:30], 40)
    assert np.isnan(x[30:]).all()  # lost: a gap, not a line to zero


@pytest.fixture
def located_run(tmp_path):
    """Flying north at 5 m, heading east, level, over a target 1.25 m ahead of it (a down camera, 90 deg wide,
    its box's centre 8 px above the picture's); the box is lost after 30 of 40 frames. It is detected too, with a
    boat 1.25 m to its right, for the first 20."""
    core = FakeCore()
    core.camera = CameraModel.from_hfov(64, 48, 90.0)
    recorder = Recorder.open(RecordingConfig(runs_dir=str(tmp_path)), {}, telemetry_expected=True)
    core.attach(recorder)
    image = np.zeros((48, 64, 3), np.uint8)
    for i in range(40):
        north = 0.1 * i
        core.telemetry.apply({"north_m": north, "east_m": -2.0, "lat_deg": 47.0 + math.degrees(north / 6_371_000),
                              "lon_deg": 8.0, "abs_alt_m": 505.0, "rel_alt_m": 5.0, "roll_deg": 0.0, "pitch_deg": 0.0,
                              "yaw_deg": 90.0, "in_air": True})
        time.sleep(0.004)
        found = (Detected((27, 11, 11, 11), "car", 0.9), Detected((35, 11, 11, 11), "boat", 0.4)) if i < 20 else None
        core.process(image, i, lambda result, i=i, found=found: (
            setattr(result, "box", (27, 11, 11, 11) if i < 30 else None), setattr(result, "detections", found)))
    recorder.close()
    return recorder.run_dir


def test_the_track_shows_the_target_positions_in_local_metres(located_run):
    write_report(located_run)
    assert (located_run / "track.png").read_bytes().startswith(b"\x89PNG")
    frames = dataset.load(located_run).frames
    ax = draw(dataset.load(located_run))["track.png"].axes[0]
    (targets,) = (c for c in ax.collections if c.get_label().startswith("target"))
    recorded = frames[frames["target_status"] == "ok"]
    assert len(recorded) == 30 and targets.get_label() == "target (30 frames geo-located)"
    east, north = targets.get_offsets().T
    # straight ahead (east) of where each frame was taken, to the 1e-8 degrees (1 mm) frames.csv keeps
    assert np.allclose(north, recorded["north_m"], atol=0.002)
    assert np.allclose(east, recorded["east_m"] + 1.25, atol=0.002)
    low, high = ax.get_xlim()
    assert low < east.min() and east.max() < high
    # each detection where its frame saw it: the car on the target, the boat 8 px (1.25 m) to its right: south
    (detected,) = (c for c in ax.collections if c.get_label().startswith("detections"))
    assert detected.get_label() == "detections (40 geo-located)"
    east, north = detected.get_offsets().T
    first = recorded.iloc[:20]
    assert np.allclose(north, np.column_stack([first["north_m"], first["north_m"] - 1.25]).ravel(), atol=0.002)
    assert np.allclose(east, np.repeat(first["east_m"].to_numpy(dtype=np.float64) + 1.25, 2), atol=0.002)


def test_processing_rate_has_no_start_up_spike():
    done = np.concatenate([[0.0, 0.0005, 0.001, 0.0015], 0.002 + np.arange(1, 120) / 30])  # a burst, then 30 FPS
    t_s = pd.Series(done + 2.0)
    _, rate = processing_rate(t_s, pd.Series(done))
    assert len(rate) and rate.max() <= 34 and np.median(rate) == pytest.approx(30, abs=1)


def test_report_html_is_one_self_contained_page(hover_run):
    paths, text = write_report(hover_run)
    assert [p.name for p in paths] == [*PLOTS, "summary.txt", "report.html"]
    page = (hover_run / "report.html").read_text()
    images = re.findall(r'src="data:image/png;base64,([^"]+)"', page)
    assert [base64.b64decode(image) for image in images] == [(hover_run / name).read_bytes() for name in PLOTS]
    assert text.splitlines()[0].replace("->", "-&gt;") in page
    assert "rtsp://pilot:***@192.0.2.1/cam" in page and "secret" not in page  # safe to copy off the drone
    outside_images = re.sub(r'"data:[^"]*"', '""', page)  # base64 may spell "http" by chance
    assert not re.search(r'(src|href)="(?!")', outside_images) and "http" not in outside_images  # nothing fetched
