"""What a new user reads after a flight (#46): ``uav-tui report`` and ``uav-tui replay`` on one small run flown in the
module with the built-in simulator, and ``uav-tui eval`` through a pipe."""

from __future__ import annotations

import csv
import html
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.evaluation.conftest import write_video_sequence

ROOT = Path(__file__).resolve().parents[2]

PROCESSOR = '''
class TooFast:
    """Asks for more than max_speed (flown clamped), raises on frames 5 and 6, misspells its F-key method."""

    def __init__(self):
        self.tmMgr = None
        self.frames = 0

    def photo_processing(self, frame):
        self.frames += 1
        if self.frames in (5, 6):
            raise ValueError(f"bad frame {self.frames}")

    def getPreparedVector(self):
        return (50.0, 0.0, 0.5)

    def customise_processing(self, id):
        pass
'''

FLIGHT = "arm\ntakeoff 3\nwait 6\nautonomy on\nwait 3\nquit\n"
"""Autonomy on at 3 m for 3 s: every vector asks 50 m/s, so each one flown is clamped."""


def uav(*args: str, cwd: Path, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "uav_tui", *args], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout)


@pytest.fixture(scope="module")
def flown(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The run folder of one headless flight on the built-in vehicle."""
    folder = tmp_path_factory.mktemp("flight")
    (folder / "fast.py").write_text(PROCESSOR)
    (folder / "flight.txt").write_text(FLIGHT)
    result = uav("--no-ui", "--fc", "sim", "--source", "synthetic:?fps=15", "--processor", "fast.py:TooFast",
                 "--script", "flight.txt", "--runs-dir", "runs", cwd=folder)
    assert result.returncode == 0, result.stderr
    assert "did you mean customize_processing?" in result.stdout  # said at load, as a warning
    (run,) = (folder / "runs").iterdir()
    return run


@pytest.fixture(scope="module")
def reported(flown: Path) -> Path:
    """The flight's folder once ``uav-tui report`` wrote into it."""
    result = uav("report", str(flown), cwd=flown)
    assert result.returncode == 0, result.stderr
    return flown


def test_the_summary_counts_clamped_vectors_as_executed_as_the_track_does(reported: Path) -> None:
    flown = reported
    text = (flown / "summary.txt").read_text()
    executed = int(re.search(r"vectors: \d+ proposed, (\d+) executed", text).group(1))
    with (flown / "frames.csv").open() as frames:
        decisions = [row["decision"] for row in csv.DictReader(frames)]
    clamped = [d for d in decisions if d.startswith("executed (")]
    assert clamped and executed == len([d for d in decisions if d.startswith("executed")])  # before: 0 of them


def test_the_report_lists_the_warnings_and_errors_it_counts(reported: Path) -> None:
    flown = reported
    text = (flown / "summary.txt").read_text()
    counted = re.search(r"events: \d+ \((\d+) warnings, (\d+) errors\)", text)
    listed = re.findall(r"^  -?[\d.]+ s (warning|error) ", text, re.MULTILINE)
    assert listed.count("warning") == int(counted.group(1)) and listed.count("error") == int(counted.group(2))
    assert "warning processor: TooFast.customise_processing is not a name the platform calls" in text
    assert re.search(r"error processor: frame \d+: Traceback \(most recent call last\): \.\.\. ValueError: bad frame 5",
                     text), text
    assert html.escape("did you mean customize_processing?") in (flown / "report.html").read_text()


def test_replay_says_the_errors_its_run_recorded_and_exits_1(flown: Path) -> None:
    result = uav("replay", str(flown), "--speed", "max", cwd=flown)
    assert result.returncode == 1, result.stderr  # before: 0, "replayed 1/1" and nothing else
    line = result.stdout.splitlines()[-1]
    said = re.search(r"; (\d+) errors, (\d+) warnings? \(uav-tui report lists them\) -> (\S+)$", line)
    assert said, line
    with (Path(said.group(3)) / "events.csv").open() as events:
        levels = [row["level"] for row in csv.DictReader(events)]
    assert int(said.group(1)) == levels.count("error") == 2  # frames 5 and 6 raised again
    assert int(said.group(2)) == levels.count("warning")
    assert "1 of 1 replays had errors (exit status 1)" in result.stderr


def test_eval_through_a_pipe_prints_a_line_per_finished_job(tmp_path: Path) -> None:
    for name in ("one", "two"):
        write_video_sequence(tmp_path / "data" / name)
    result = uav("eval", "data", "-p", "cv:mil", "--workers", "1", "--out", "out", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    progress = [line for line in result.stdout.splitlines() if line.startswith("eval: ")]
    assert [line.split(":")[1] for line in progress] == [" 1/2 cv", " 2/2 cv"], result.stdout
    assert all(re.search(r"cv:mil on (one|two): AUC \d\.\d{3}, [\d.]+ ms/frame$", line) for line in progress)
