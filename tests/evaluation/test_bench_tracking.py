"""``scripts/bench_tracking.py``: its per-tracker counts, its goal verdicts, and a tracker that is missing.

Cheap: a six-frame generated sequence and processors with known answers; no timing is asserted.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import pytest

from tests.scripts import script_module
from uav_tui.evaluation import TrackerSpec

ROOT = Path(__file__).resolve().parents[2]
TRACKERS = Path(__file__).with_name("trackers.py")


@pytest.fixture(scope="module")
def bench() -> Iterator[ModuleType]:
    with script_module("bench_tracking") as module:
        yield module


def test_counts_per_tracker_and_a_missing_or_failing_tracker_is_named_not_fatal(bench: ModuleType,
                                                                                video_sequence: Path,
                                                                                tmp_path: Path) -> None:
    replay = TrackerSpec(f"{TRACKERS}:ReplaysBoxes", {"boxes": str(video_sequence / "gt.txt")})
    never = TrackerSpec(f"{TRACKERS}:NeverFinds")
    failing = TrackerSpec(f"{TRACKERS}:Failing", {"frame": 3})
    document = bench.run(video_sequence.parent, [replay, never, failing, TrackerSpec("no_such_tracker")], 1, 1,
                         tmp_path / "out")
    assert list(document["missing"]) == ["no_such_tracker"]
    assert "no_such_tracker" in document["missing"]["no_such_tracker"]
    assert list(document["failed"]) == [failing.label]
    assert document["failed"][failing.label]["moving-box"].startswith("frame 3: ValueError: bad reshape on frame 3")
    assert failing.label not in document["trackers"]
    # the gt has 5 visible frames and 1 absent one; the replay reports none exactly on the absent one
    assert document["trackers"][replay.label].items() >= {
        "visible_frames": 5, "lost_while_visible": 0, "lost_while_visible_share": 0.0, "absent_frames": 1,
        "absent_reported_lost": 1, "absent_reported_lost_share": 1.0}.items()
    assert document["trackers"][replay.label]["success_auc"] == pytest.approx(20 / 21, abs=1e-4)
    assert document["trackers"][never.label]["lost_while_visible_share"] == 1.0
    assert document["trackers"][never.label]["success_auc"] == 0
    verdict = document["goals"]["csrt mode=fast"]["success AUC minus cv:csrt's"]
    assert verdict["pass"] is None and "missing" in verdict["why"]
    assert bench.goals({}, {failing.label})["nanotrack"]["share of visible frames lost"]["pass"] is None
    assert (tmp_path / "out" / "eval.json").is_file()


def test_goals_are_ratios_within_the_run_with_pass_or_fail(bench: ModuleType) -> None:
    def scores(auc: float, p20: float, ms: float, lost: float = 0.0, absent: float | None = None) -> dict:
        return {"success_auc": auc, "precision_20": p20, "ms_mean": ms, "lost_while_visible_share": lost,
                "absent_reported_lost_share": absent}

    trackers = {"nanotrack": scores(0.625, 0.7, 7.0, lost=0.01, absent=0.4), "cv:nano": scores(0.6, 0.75, 6.0),
                "csrt mode=fast": scores(0.5, 0.6, 5.0), "cv:csrt": scores(0.5, 0.6, 20.0)}
    verdicts = bench.goals(trackers, set())
    nano = verdicts["nanotrack"]
    assert nano["success AUC minus cv:nano's"] == {"goal": ">= 0.02", "value": 0.025, "pass": True}
    assert nano["precision@20 minus cv:nano's"]["pass"] is False
    assert nano["share of visible frames lost"]["pass"] is True
    assert nano["share of absent frames reported lost"]["pass"] is False
    assert nano["ms/frame over cv:nano's"] == {"goal": "<= 1.2", "value": 1.1667, "pass": True}
    assert all(verdict["pass"] for verdict in verdicts["csrt mode=fast"].values())
    assert verdicts["csrt mode=fast"]["ms/frame over cv:csrt's"]["value"] == 0.25
    unusable = bench.goals(trackers, {"cv:nano"})["nanotrack"]
    assert unusable["success AUC minus cv:nano's"]["pass"] is None
    assert unusable["share of visible frames lost"]["pass"] is True  # needs nanotrack alone
