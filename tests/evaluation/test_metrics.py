"""Eval metrics against values computed by hand."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from uav_tui.evaluation.metrics import iou, score_sequence, summarise

GT = np.array([[0, 0, 20, 10], [10, 10, 20, 10], [np.nan] * 4, [30, 0, 20, 10]], dtype=float)
TIMES = np.array([1.0, 2.0, 3.0, 4.0])


def test_a_perfect_tracker_scores_20_of_21() -> None:
    scores = score_sequence(GT.copy(), GT, TIMES)
    assert scores.success_auc == pytest.approx(20 / 21)  # IoU 1 exceeds every threshold but 1
    assert scores.precision_20 == 1.0 and scores.norm_precision == 1.0
    assert (scores.frames, scores.scored, scores.frames_lost) == (4, 3, 0)  # the NaN frame is not scored
    assert (scores.ms_mean, scores.ms_p50, scores.fps) == (2.5, 2.5, 400.0)


def test_a_tracker_that_is_always_lost_scores_zero() -> None:
    scores = score_sequence(np.full_like(GT, np.nan), GT, TIMES)
    assert (scores.success_auc, scores.precision_20, scores.norm_precision) == (0.0, 0.0, 0.0)
    assert scores.frames_lost == 3


def test_a_box_shifted_by_half_its_width() -> None:
    shifted = GT + [10, 0, 0, 0]  # IoU 100 / 300 = 1/3: above the thresholds 0 .. 0.30 (7 of 21)
    assert iou(shifted[:1], GT[:1])[0] == pytest.approx(1 / 3)
    scores = score_sequence(shifted, GT, TIMES)
    assert scores.success_auc == pytest.approx(7 / 21)
    assert scores.precision_20 == 1.0  # 10 px off
    assert scores.precision_curve[9] == 0.0 and scores.precision_curve[10] == 1.0
    # normalised error 10 / 20 = 0.5: within the last threshold only (0.5 of 0, 0.01, ..., 0.5)
    assert scores.norm_precision == pytest.approx(1 / 51)


def test_what_is_reported_on_a_hidden_frame_counts_only_as_not_reported_lost() -> None:
    pred = GT.copy()
    pred[2] = [100, 100, 5, 5]
    boxed, lost = score_sequence(pred, GT, TIMES), score_sequence(GT.copy(), GT, TIMES)
    assert (boxed.absent_frames, boxed.absent_lost, boxed.absent_lost_share) == (1, 0, 0.0)
    assert (lost.absent_frames, lost.absent_lost, lost.absent_lost_share) == (1, 1, 1.0)
    assert dataclasses.replace(boxed, absent_lost=1, absent_lost_share=1.0, frames_to_lost=0.0) == lost


def test_a_reappearance_counts_as_found_again_only_within_a_second() -> None:
    gt = np.array([[0, 0, 20, 10]] * 2 + [[np.nan] * 4] * 3 + [[0, 0, 20, 10]] * 4, dtype=float)
    times = np.ones(len(gt))
    late = gt.copy()
    late[2:7] = np.nan  # lost from the first absent frame; back 2 frames after the target
    assert (score_sequence(late, gt, times, fps=3.0).reacquired, score_sequence(late, gt, times, fps=2.0).reacquired,
            score_sequence(late, gt, times, fps=2.0).reappearances) == (1, 0, 1)
    slow = gt.copy()
    slow[2:4] = [40, 40, 20, 10]  # a box on nothing for 2 of the 3 absent frames, then reported lost
    slow[4:] = np.nan
    scores = score_sequence(slow, gt, times, fps=2.0)
    assert (scores.disappearances, scores.frames_to_lost, scores.reacquired) == (1, 2.0, 0)
    assert scores.reacquired_share == 0.0
    kept = np.nan_to_num(gt, nan=40.0)  # a box on every absent frame: never reported lost, the whole absence
    never = score_sequence(kept, gt, times, fps=2.0)
    assert (never.frames_to_lost, never.reacquired) == (3.0, 1)
    overall = summarise([scores, never], np.ones(2 * len(gt)))
    assert (overall.frames_to_lost, overall.reacquired, overall.reappearances) == (2.5, 1, 2)


def test_without_absent_frames_there_is_no_share() -> None:
    scores = score_sequence(GT[[0, 1, 3]], GT[[0, 1, 3]], TIMES[:3])
    assert (scores.absent_frames, scores.absent_lost, scores.absent_lost_share) == (0, 0, None)
    assert summarise([scores], TIMES[:3]).absent_lost_share is None


def test_overall_scores_average_the_sequences_and_add_the_frames() -> None:
    perfect = score_sequence(GT.copy(), GT, TIMES)
    lost = score_sequence(np.full_like(GT, np.nan), GT, TIMES)
    overall = summarise([perfect, lost], np.concatenate([TIMES, TIMES]))
    assert overall.success_auc == pytest.approx(10 / 21)
    assert (overall.frames, overall.scored, overall.frames_lost) == (8, 6, 3)
