"""``uav-tui eval`` left running: a failing job fails alone, results are kept as jobs finish, ``--resume``, the
processor's ``tmMgr``, the loss columns, ``--threads``, and bad inputs."""

from __future__ import annotations

import io
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tests.evaluation.conftest import BOXES, write_gt, write_video_sequence
from uav_tui.cli import main
from uav_tui.evaluation import TrackerSpec, evaluate, find_sequences
from uav_tui.evaluation.report import summary, table

ROOT = Path(__file__).resolve().parents[2]
TRACKERS = Path(__file__).with_name("trackers.py")
SHIFTED = BOXES + [20, 0, 0, 0]
"""The target of a second sequence: its first box starts at x = 30 (the first sequence's at 10)."""


def two_sequences(tmp_path: Path) -> Path:
    data = tmp_path / "data"
    write_video_sequence(data / "a-first")
    write_video_sequence(data / "b-second", SHIFTED)
    return data


def test_a_processor_that_raises_on_frame_5_fails_that_job_alone(tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    data, out = two_sequences(tmp_path), tmp_path / "out"
    code = main(["eval", str(data), "-p", f"{TRACKERS}:Failing", "--processor-arg", "first_x=30",
                 "-p", f"{TRACKERS}:ReplaysBoxes", "--processor-arg", f'boxes="{data / "a-first" / "gt.txt"}"',
                 "--workers", "1", "--out", str(out)])
    printed = capsys.readouterr().out
    assert code == 1
    # the tracker's cell folds a long path (the clone's), so the row is matched without it; the summary names it
    assert re.search(r"b-second\s+│[^│\n]*│\s+failed\s+│\s+frame 5", printed), printed
    assert f"{TRACKERS}:Failing first_x=30 on b-second failed at frame 5: ValueError: bad reshape on frame 5 " \
           "(trackers.py:" in " ".join(printed.split())
    assert "1 of 4 jobs failed" in printed

    document = json.loads((out / "eval.json").read_text())
    failing, replaying = document["trackers"].values()
    assert failing["failed"]["b-second"]["at"] == "frame 5"
    assert "raise ValueError" in failing["failed"]["b-second"]["traceback"]
    assert list(failing["sequences"]) == ["a-first"] and failing["overall"]["frames"] == 6
    assert list(replaying["sequences"]) == ["a-first", "b-second"] and replaying["overall"]["frames"] == 12
    assert replaying["sequences"]["a-first"]["success_auc"] == pytest.approx(20 / 21)
    assert (document["jobs_done"], document["jobs_total"], document["jobs_failed"]) == (4, 4, 1)
    assert (out / "success.png").is_file()


def _eval_in_a_process(data: Path, out: Path, hold: Path, log: Path, *more: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "uav_tui", "eval", str(data), "-p", f"{TRACKERS}:Failing", "--processor-arg",
         f'hold="{hold}"', "--processor-arg", f'log="{log}"', "--processor-arg", "first_x=30", "--workers", "1",
         "--out", str(out), *more],
        cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)}, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, preexec_fn=_ctrl_c_as_at_a_terminal)


def _ctrl_c_as_at_a_terminal() -> None:
    """SIGINT's default action in the eval: a suite started in the background (``cmd &`` in a script) has it
    ignored, and an ignored signal stays ignored in every process started from there, Python's too."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def test_a_killed_eval_keeps_the_finished_jobs_and_resume_runs_the_rest(tmp_path: Path,
                                                                          capsys: pytest.CaptureFixture[str]) -> None:
    data, out, hold, log = two_sequences(tmp_path), tmp_path / "out", tmp_path / "hold", tmp_path / "log"
    hold.touch()  # the job on b-second waits on its frame 5 until this file goes
    process = _eval_in_a_process(data, out, hold, log)
    try:
        deadline = time.monotonic() + 90
        while not (out / "eval.json").is_file() and time.monotonic() < deadline and process.poll() is None:
            time.sleep(0.1)
        time.sleep(0.5)  # well into the second job, which waits
        process.send_signal(signal.SIGKILL)  # as a crash or the OOM killer would: nothing runs after this
    finally:
        process.kill()
        process.communicate(timeout=10)
    document = json.loads((out / "eval.json").read_text())
    (entry,) = document["trackers"].values()
    assert list(entry["sequences"]) == ["a-first"] and entry["overall"]["frames"] == 6
    assert (document["jobs_done"], document["jobs_total"]) == (1, 2)
    assert log.read_text().split() == ["10", "30"]  # both jobs started; only the first finished

    hold.unlink()
    log.unlink()
    args = ["eval", str(data), "-p", f"{TRACKERS}:Failing", "--processor-arg", f'hold="{hold}"',
            "--processor-arg", f'log="{log}"', "--processor-arg", "first_x=30", "--workers", "1"]
    assert main([*args, "--resume", str(out)]) == 0
    assert "resuming: 1 of 2 jobs already done" in capsys.readouterr().out
    assert log.read_text().split() == ["30"]  # a-first was not run again
    document = json.loads((out / "eval.json").read_text())
    (entry,) = document["trackers"].values()
    assert sorted(entry["sequences"]) == ["a-first", "b-second"] and document["jobs_done"] == 2

    assert main([*args, "--out", str(out)]) == 2  # not over an earlier evaluation by mistake
    assert f"{out} already holds an evaluation (jobs.jsonl): go on with it with --resume" in capsys.readouterr().err
    assert main([*args, "--resume", str(out), "--threads", "2"]) == 2
    assert "resume with the same --threads" in capsys.readouterr().err


def test_ctrl_c_says_what_is_kept_and_how_to_go_on(tmp_path: Path) -> None:
    data, out, hold, log = two_sequences(tmp_path), tmp_path / "out", tmp_path / "hold", tmp_path / "log"
    hold.touch()
    process = _eval_in_a_process(data, out, hold, log)
    try:
        deadline = time.monotonic() + 90
        while not (out / "eval.json").is_file() and time.monotonic() < deadline and process.poll() is None:
            time.sleep(0.1)
        time.sleep(0.5)
        process.send_signal(signal.SIGINT)
        _, err = process.communicate(timeout=30)
    finally:
        process.kill()
        process.communicate(timeout=10)
    assert process.returncode == 130
    assert f"interrupted; the 1 finished jobs are in {out / 'eval.json'}; go on with: uav-tui eval" in err
    assert f"--resume {out}" in err


def test_the_manual_example_processor_evaluates(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    page = (ROOT / "docs" / "writing-a-processor.md").read_text()
    code = re.search(r"```python\n(# ~/algos/mine.py.*?)```", page, re.S)
    assert code, "the manual's example processor"
    (tmp_path / "mine.py").write_text(code.group(1))
    data, out = tmp_path / "data", tmp_path / "out"
    write_video_sequence(data / "moving-box")
    assert main(["eval", str(data), "-p", f"{tmp_path / 'mine.py'}:MyAnalyzer", "--out", str(out)]) == 0
    saves = [json.loads(line) for line in (out / "saves").glob("*/moving-box/saves.jsonl").__next__().read_text()
             .splitlines()]
    # 6 frames at 10 FPS (0.5 s) and a save a second of the frames' time: frame 1 only, with the example's fields
    assert [(s["frame"], s["t_s"], sorted(s["extra"])) for s in saves] == [(1, 0.0, ["brightest_x", "brightest_y"])]
    assert "1/1" in capsys.readouterr().out  # saved: stored / called


def test_tm_mgr_gives_the_frame_clock_saves_are_capped_and_threads_set(tmp_path: Path,
                                                                      capsys: pytest.CaptureFixture[str]) -> None:
    data, out = tmp_path / "data", tmp_path / "out"
    write_video_sequence(data / "moving-box")
    assert main(["eval", str(data), "-p", f"{TRACKERS}:ThreadsProbe", "--threads", "2", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "OpenCV/ONNX threads per job: 2" in printed
    saves = [json.loads(line) for line in next((out / "saves").glob("*/moving-box/saves.jsonl")).read_text()
             .splitlines()]
    # 10 saves a second of the frames' time: within save_max_hz's burst (5) for these 0.5 s.
    assert [s["extra"]["seq"] for s in saves] == [1, 2, 3, 4, 5, 6]
    assert [s["extra"]["t_s"] for s in saves] == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4, 0.5])
    assert {s["extra"]["threads"] for s in saves} == {2} and {s["extra"]["alt"] for s in saves} == {None}
    assert sorted(p.name for p in next((out / "saves").glob("*/moving-box")).glob("*.jpg")) == [
        f"{n:06d}.jpg" for n in range(1, 7)]
    assert re.search(r"moving-box .* 6/6 │", printed), printed
    assert json.loads((out / "eval.json").read_text())["threads"] == 2


def test_the_loss_columns_against_hand_computed_values(tmp_path: Path) -> None:
    data = tmp_path / "data"
    hidden_twice = BOXES.copy()
    hidden_twice[3] = np.nan  # gt NaN on frames 2 and 3 (0-based)
    write_video_sequence(data / "a-once")
    write_video_sequence(data / "b-twice", hidden_twice)
    reported = BOXES.copy()
    reported[1] = reported[2] = np.nan  # lost on frame 1 (visible in both) and frame 2 (absent in both)
    boxes = write_gt(tmp_path / "reported.txt", reported)
    results = evaluate(find_sequences([data]), [TrackerSpec(f"{TRACKERS}:ReplaysBoxes", {"boxes": str(boxes)})],
                       workers=1)
    once, twice = (r.scores for r in results)
    assert (once.frames_lost, once.absent_frames, once.absent_lost, once.absent_lost_share) == (1, 1, 1, 1.0)
    assert (twice.frames_lost, twice.absent_frames, twice.absent_lost, twice.absent_lost_share) == (1, 2, 1, 0.5)
    (overall,) = (entry["overall"] for entry in summary(results)["trackers"].values())
    assert (overall["frames_lost"], overall["absent_frames"], overall["absent_lost"]) == (2, 3, 2)
    assert overall["absent_lost_share"] == pytest.approx(0.75)  # the mean of the sequences' shares
    rows = {row.split("│")[1].strip(): [c.strip() for c in row.split("│")[3:]]
            for row in _render(table(results)).splitlines() if row.count("│") > 5}
    assert (rows["a-once"][3], rows["a-once"][4]) == ("1", "100%")
    assert (rows["b-twice"][3], rows["b-twice"][4]) == ("1", "50%")
    assert (rows["overall"][3], rows["overall"][4]) == ("2", "75%")


def _render(grid) -> str:
    from rich.console import Console

    console = Console(width=200, record=True, file=io.StringIO())
    console.print(grid)
    return console.export_text()


@pytest.mark.parametrize("first", ["5000,5000,30,30", "1e30,1e30,30,30", "-100,10,20,16"])
def test_a_first_box_outside_the_frame_is_refused_with_the_line_named(tmp_path: Path, first: str,
                                                                      capsys: pytest.CaptureFixture[str]) -> None:
    folder = write_video_sequence(tmp_path / "data" / "bad")
    gt = folder / "gt.txt"
    gt.write_text(first + "\n" + "".join(gt.read_text().splitlines(keepends=True)[1:]))
    assert main(["eval", str(folder), "-p", "cv:csrt", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{gt}:1: the first box" in err and "is outside the 96x64 frame" in err
    assert not (tmp_path / "out").exists()  # refused before any job


def test_a_first_box_the_tracker_cannot_take_fails_its_job_alone(tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    data = tmp_path / "data"
    write_video_sequence(data / "a-fine")
    huge = write_video_sequence(data / "b-huge")
    gt = huge / "gt.txt"
    gt.write_text("0,0,1e30,1e30\n" + "".join(gt.read_text().splitlines(keepends=True)[1:]))
    assert main(["eval", str(data), "-p", "cv:csrt", "--workers", "1", "--out", str(tmp_path / "out")]) == 1
    printed = " ".join(capsys.readouterr().out.split())
    assert "cv:csrt on b-huge failed at frame 1: error: OpenCV" in printed  # it starts on the first frame
    document = json.loads((tmp_path / "out" / "eval.json").read_text())
    assert list(document["trackers"]["cv:csrt"]["sequences"]) == ["a-fine"]


def test_a_nan_box_from_the_processor_is_scored_as_lost(video_sequence: Path) -> None:
    (result,) = evaluate(find_sequences([video_sequence]), [TrackerSpec(f"{TRACKERS}:ReportsBox",
                                                                        {"box": [float("nan"), 0, 10, 10]})], workers=1)
    assert np.isnan(result.boxes).all()
    assert result.scores.frames_lost == 5 and result.scores.absent_lost_share == 1.0
