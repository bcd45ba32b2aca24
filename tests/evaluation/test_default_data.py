"""``uav-tui eval`` with no sequence folder scores the aerial-tracking set where the tests find it, and says how to
get it when it is not there."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from processors.detection import DATA_DIR_ENV
from tests.evaluation.conftest import write_video_sequence
from uav_tui.cli import main


def test_no_folder_given_scores_the_set_in_the_data_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    write_video_sequence(tmp_path / "data" / "aerial-tracking" / "moving-box")
    monkeypatch.setenv(DATA_DIR_ENV, str(tmp_path / "data"))
    assert main(["eval", "-p", "cv:mil", "--workers", "1", "--out", str(tmp_path / "out")]) == 0
    document = json.loads((tmp_path / "out" / "eval.json").read_text())
    assert list(document["sequences"]) == ["moving-box"]
    assert "moving-box" in capsys.readouterr().out


@pytest.mark.parametrize(("data", "said"), [("empty", "aerial-tracking is not here"),
                                            ("nowhere", f"{DATA_DIR_ENV}=")], ids=["no-set-in-it", "no-folder"])
def test_no_folder_given_and_no_set_says_how_to_get_it(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                       capsys: pytest.CaptureFixture[str], data: str,
                                                       said: str) -> None:
    (tmp_path / "empty").mkdir()
    monkeypatch.setenv(DATA_DIR_ENV, str(tmp_path / data))
    assert main(["eval", "-p", "cv:mil", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert said in err and "scripts/build_tracking_set.py" in err and "docs/evaluation.md" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("command", [["bench_tracking.py"], ["bench_tracking_floors.py"],
                                     ["bench_pipeline.py", "--footage", "aerial"]], ids=lambda c: c[0])
def test_a_benchmark_without_the_set_says_how_to_get_it(tmp_path: Path, command: list[str]) -> None:
    script = Path(__file__).resolve().parents[2] / "scripts" / command[0]
    done = subprocess.run([sys.executable, str(script), *command[1:]], capture_output=True, text=True, timeout=60,
                          env={**os.environ, DATA_DIR_ENV: str(tmp_path / "nowhere")})
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "scripts/build_tracking_set.py" in done.stderr
