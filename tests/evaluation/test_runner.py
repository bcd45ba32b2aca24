"""One-pass runs of real processors, the command, and the same jobs on a real Dask cluster."""

from __future__ import annotations

import json
import os
from pathlib import Path
from unittest import mock

import numpy as np
import pytest

from tests.evaluation.conftest import BOXES, write_video_sequence
from uav_tui.cli import main
from uav_tui.evaluation import TrackerSpec, evaluate, find_sequences

TRACKERS = Path(__file__).with_name("trackers.py")


def replay(gt: Path, dx: float = 0.0) -> TrackerSpec:
    return TrackerSpec(f"{TRACKERS}:ReplaysBoxes", {"boxes": str(gt), "dx": dx})


def test_one_pass_starts_on_the_first_box_and_scores_what_the_processor_reports(video_sequence: Path) -> None:
    sequences = find_sequences([video_sequence])
    perfect, shifted, lost = evaluate(sequences, [replay(video_sequence / "gt.txt"),
                                                  replay(video_sequence / "gt.txt", dx=10.0),
                                                  TrackerSpec(f"{TRACKERS}:NeverFinds")], workers=1)
    assert np.array_equal(perfect.boxes, BOXES, equal_nan=True)
    assert perfect.scores.success_auc == pytest.approx(20 / 21) and perfect.scores.frames_lost == 0
    assert shifted.scores.success_auc == pytest.approx(7 / 21)  # IoU 1/3 on every scored frame
    assert lost.scores.success_auc == 0 and lost.scores.frames_lost == 5
    assert len(perfect.times_ms) == 6 and (perfect.times_ms >= 0).all()


def test_the_command_prints_the_table_and_writes_json_and_plots(video_sequence: Path, tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    code = main(["eval", str(video_sequence.parent), "-p", f"{TRACKERS}:ReplaysBoxes", "--processor-arg",
                 f'boxes="{video_sequence / "gt.txt"}"', "-p", "cv:mil", "--workers", "2", "--out", str(out)])
    assert code == 0
    printed = capsys.readouterr().out
    assert "overall" in printed and "moving-box" in printed and "cv:mil" in printed
    document = json.loads((out / "eval.json").read_text())
    assert list(document["sequences"]) == ["moving-box"]
    replayed = document["trackers"][f"{TRACKERS}:ReplaysBoxes boxes={video_sequence / 'gt.txt'}"]
    assert replayed["overall"]["success_auc"] == pytest.approx(20 / 21)
    assert len(replayed["sequences"]["moving-box"]["success_curve"]) == 21
    assert document["trackers"]["cv:mil"]["overall"]["frames"] == 6
    for name in ("success.png", "precision.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(("args", "message"), [
    (["-p", f"{TRACKERS}:NoCatchCmd"], "has no catch_cmd"),
    (["-p", "cv:nosuch"], "OpenCV has no tracker 'nosuch'"),
    (["-p", "cv:csrt", "--processor-arg", "no_such_field=1"], "no field 'no_such_field'"),
], ids=["no-catch_cmd", "unknown-opencv-tracker", "bad-parameter"])
def test_what_cannot_be_scored_is_refused_before_any_job(video_sequence: Path, tmp_path: Path, args: list[str],
                                                         message: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["eval", str(video_sequence), *args, "--out", str(tmp_path / "out")]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_broken_sequence_stops_the_command_with_the_file_named(tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    folder = write_video_sequence(tmp_path / "seq", BOXES[:3])
    assert main(["eval", str(folder), "-p", "cv:mil", "--out", str(tmp_path / "out")]) == 2
    assert f"{folder / 'gt.txt'} has 3 rows" in capsys.readouterr().err


def test_a_dask_cluster_gives_the_same_results_as_local_workers(video_sequence: Path) -> None:
    distributed = pytest.importorskip("distributed")
    sequences = find_sequences([video_sequence])
    trackers = [TrackerSpec("cv:csrt"), TrackerSpec("csrt"), replay(video_sequence / "gt.txt", dx=3.0)]
    local = evaluate(sequences, trackers, workers=1)
    # Its nanny sets MALLOC_TRIM_THRESHOLD_ and *_NUM_THREADS in this process's environment to start its worker:
    # restored after, or the next test in this pytest process would see a user's malloc tuning (test_opencv_pool).
    with mock.patch.dict(os.environ), distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1", scheduler_port=0,
            dashboard_address="127.0.0.1:0") as cluster:
        remote = evaluate(sequences, trackers, cluster=cluster.scheduler_address)
    assert [(r.sequence, r.tracker) for r in remote] == [(r.sequence, r.tracker) for r in local]
    for here, there in zip(local, remote, strict=True):
        assert np.array_equal(here.boxes, there.boxes, equal_nan=True)
        assert here.scores.success_curve == there.scores.success_curve
        assert here.scores.precision_curve == there.scores.precision_curve
        assert here.scores.frames_lost == there.scores.frames_lost


def test_names_from_outside_reach_the_terminal_without_control_characters(tmp_path: Path,
                                                                          capsys: pytest.CaptureFixture[str]) -> None:
    hostile = "seq\x1b]2;pwned\x07\x1b[2J"
    data, out = tmp_path / "data", tmp_path / f"out{hostile}"
    write_video_sequence(data / hostile)
    # a job that fails names the sequence under the table; the written files' paths hold ESC too
    assert main(["eval", str(data), "-p", f"{TRACKERS}:NeverFinds", "-p", f"{TRACKERS}:Failing",
                 "--workers", "1", "--out", str(out)]) == 1
    printed = capsys.readouterr()
    assert "seq\\x1b]2;pwned\\x07\\x1b[2J" in printed.out and "wrote " in printed.out
    assert not {"\x1b", "\x07"} & set(printed.out + printed.err)
    broken = write_video_sequence(tmp_path / f"broken{hostile}", BOXES[:3])
    assert main(["eval", str(broken), "-p", "cv:mil", "--out", str(tmp_path / "out2")]) == 2
    err = capsys.readouterr().err
    assert "has 3 rows" in err and not {"\x1b", "\x07"} & set(err)
