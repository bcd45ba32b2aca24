"""``uav-tui report`` draws a recorded run into PNGs; ``uav-tui runs`` lists runs."""

from __future__ import annotations

import functools
import math
import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tests.recording.recorder_fakes import FakeCore
from uav_tui.config import RecordingConfig
from uav_tui.recorded.report import PLOTS, write_report
from uav_tui.recorded.runs_cli import main
from uav_tui.recording import Recorder

ROOT = Path(__file__).resolve().parents[2]


def _circle_processor(core, i, result):
    core.telemetry.save(result.frame.image, target_x=float(i), confidence=0.5 + i / 200)
    result.vector = (0.5, 0.0, 1.0) if i % 10 == 1 else None
    result.decision = "executed" if result.vector else "no vector"


@pytest.fixture
def circle_run(tmp_path):
    """A run flown on a 5 m circle: 80 telemetry samples, a frame after every second one, vectors on some."""
    core = FakeCore()
    recorder = Recorder.open(RecordingConfig(runs_dir=str(tmp_path)), {"processor": {"name": "circle"}},
                             telemetry_expected=True)
    core.attach(recorder)
    image = np.zeros((48, 64, 3), np.uint8)
    for i in range(80):
        angle = i / 80 * 2 * math.pi
        core.telemetry.apply({"north_m": 5 * math.cos(angle), "east_m": 5 * math.sin(angle), "down_m": -3.0,
                              "rel_alt_m": 3.0 + 0.1 * math.sin(3 * angle), "roll_deg": 5 * math.sin(angle),
                              "pitch_deg": -2.0, "yaw_deg": math.degrees(angle) - 180, "in_air": True})
        time.sleep(0.004)
        if i % 2:
            core.process(image, i, functools.partial(_circle_processor, core, i))
    core.events.emit("error", "processor", "frame 7: ValueError")
    recorder.close()
    return recorder.run_dir


def test_report_writes_every_plot_and_a_summary(circle_run):
    paths, text = write_report(circle_run)
    assert [p.name for p in paths] == [*PLOTS, "summary.txt", "report.html"]
    for path in paths[:len(PLOTS)]:
        data = path.read_bytes()
        assert data.startswith(b"\x89PNG") and len(data) > 15_000, path.name
    assert "frames: 40 processed" in text and "40 saved" in text
    assert "vectors: 8 proposed, 8 executed" in text
    assert "telemetry: 80 samples, flown 31." in text  # a 5 m circle is 31.4 m round
    assert "1 errors" in text
    assert (circle_run / "summary.txt").read_text() == text + "\n"


def test_runs_lists_runs_and_report_finds_them_by_name(circle_run, capsys):
    runs_dir = str(circle_run.parent)
    assert main("runs", ["--runs-dir", runs_dir]) == 0
    listing = capsys.readouterr().out
    assert circle_run.name in listing and "     40 " in listing
    assert main("report", [circle_run.name, "--runs-dir", runs_dir]) == 0
    assert f"wrote {circle_run / 'track.png'}" in capsys.readouterr().out
    assert main("report", ["--runs-dir", runs_dir]) == 0  # the newest run by default
    assert main("report", ["no-such-run", "--runs-dir", runs_dir]) == 2
    assert "uav-tui runs" in capsys.readouterr().err


def test_report_on_a_run_without_telemetry(tmp_path):
    recorder = Recorder.open(RecordingConfig(runs_dir=str(tmp_path)), {}, telemetry_expected=False)
    recorder.close()
    paths, text = write_report(recorder.run_dir)
    assert all(p.is_file() for p in paths)
    assert "frames: 0 processed" in text and "telemetry: none" in text


def _limit_files_to(size: int):
    """A ``preexec_fn``: files of the process cannot grow past ``size`` bytes; writes past it fail (EFBIG) as they
    would on a full disk (see tests/recording/test_recorder_full_disk.py)."""
    def limit() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))
    return limit


def test_report_on_a_full_disk_says_so_once_and_leaves_no_half_written_file(circle_run):
    paths, _ = write_report(circle_run)  # an earlier report: kept whole
    before = (circle_run / "report.html").read_bytes()
    largest_plot = max(path.stat().st_size for path in paths[:len(PLOTS)])
    assert len(before) > largest_plot + 4096
    (circle_run / "summary.txt").unlink()
    result = subprocess.run([sys.executable, "-m", "uav_tui", "report", str(circle_run)], capture_output=True,
                            text=True, timeout=120, env={**os.environ, "PYTHONPATH": str(ROOT)},
                            preexec_fn=_limit_files_to(largest_plot + 4096))  # the plots fit, report.html does not
    # Before: a traceback, and report.html cut at the limit.
    assert result.returncode == 5, result.stdout + result.stderr
    assert "Traceback" not in result.stderr and result.stderr.count("\n") == 1, result.stderr
    assert f"{circle_run / 'report.html'}: File too large" in result.stderr and "run it again" in result.stderr
    assert (circle_run / "report.html").read_bytes() == before
    assert (circle_run / "summary.txt").is_file()  # written whole before it
    assert not list(circle_run.glob("*.tmp"))


def test_report_says_where_the_telemetry_has_gaps(circle_run):
    path = circle_run / "telemetry.csv"
    table = pd.read_csv(path, dtype={"t_mono_ns": "Int64", "t_wall_ns": "Int64"})
    later = table.index >= 40
    table.loc[later, ["t_mono_ns", "t_wall_ns"]] += 10_000_000_000  # 10 s without telemetry half-way round
    table.to_csv(path, index=False)
    _, text = write_report(circle_run)
    assert "telemetry gaps: 1 of 2 s or more (10.0 s at " in text
    assert "telemetry gaps" in (circle_run / "report.html").read_text()
