"""``scripts/bench_tracking_floors.py``: its Pareto front and goal verdict, and the NanoTrack oracle's rules.

Cheap: rows with known values and a six-frame generated sequence; no timing is asserted.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from tests.scripts import script_module
from uav_tui.evaluation import load_sequence

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def floors() -> Iterator[ModuleType]:
    with script_module("bench_tracking_floors") as module:
        yield module


def test_front_marks_the_settings_no_other_beats_and_the_ones_that_meet_the_goal(floors: ModuleType) -> None:
    base = {"auc": 0.47, "cpu_ms": 50.0}
    rows = [{"setting": "a", "auc": 0.47, "cpu_ms": 26.0},  # as good, just over half the CPU
            {"setting": "b", "auc": 0.46, "cpu_ms": 22.0},
            {"setting": "c", "auc": 0.45, "cpu_ms": 23.0},  # beaten by b: less AUC at more CPU
            {"setting": "d", "auc": 0.48, "cpu_ms": 25.0}]  # meets the goal, and beats a
    result = floors.front(base, rows)
    assert [row["pareto"] for row in result["settings"]] == [False, True, False, True]
    assert result["meets_goal"] == ["d"]
    assert result["best_auc_at_half_cpu"] == 0.48
    assert floors.front(base, rows[:3])["meets_goal"] == []


def test_the_oracle_reports_no_box_exactly_where_the_target_is_absent(floors: ModuleType,
                                                                      video_sequence: Path) -> None:
    sequence = load_sequence(video_sequence)
    absent = np.isnan(sequence.gt).any(axis=1)
    plain, oracle = floors.nano_run(sequence, oracle=False), floors.nano_run(sequence, oracle=True)
    assert plain.absent_lost == 0 and oracle.absent_lost == int(absent.sum()) == 1
    assert oracle.frames_lost == 0 and oracle.success_auc >= plain.success_auc
