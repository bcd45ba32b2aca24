"""The reference tracker on real drone video (``shared/data/aerial-tracking``), run as ``uav-tui eval`` runs it.

On these two sequences plain OpenCV CSRT never reports a failure and its IoU with the ground truth stays
above a floor on every frame (person12_1: 0.56, boat5: 0.35, measured). The fast tracker must hold the
target as well: report a box on every frame (no false loss) and keep every frame's IoU above MIN_IOU
(that floor less 0.15), its mean IoU within MEAN_GAP of plain CSRT's. A correctness bound, not a timing
one. The fast settings match plain CSRT over the whole 19-sequence set, not on each sequence: on boat5
(a large target, resampled to a 128-px template) the first box decides much, moving it by one pixel
takes fast's success AUC from 0.384 to 0.509 and plain CSRT's from 0.579 to 0.564.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from uav_tui.evaluation import Job, TrackerSpec, load_sequence, run_job
from uav_tui.evaluation.metrics import iou

MIN_IOU = {"uav123_10fps-person12_1": 0.4, "uav123_10fps-boat5": 0.19}
"""Per sequence: the IoU every frame must keep; plain CSRT keeps at least 0.15 more."""
MEAN_GAP = {"uav123_10fps-person12_1": 0.15, "uav123_10fps-boat5": 0.25}
"""Per sequence: how far fast's mean IoU may fall below plain CSRT's (boat5 measured: 0.377 against 0.583)."""


@pytest.mark.parametrize("name", sorted(MIN_IOU))
def test_fast_tracker_holds_the_target_on_every_frame_like_plain_csrt(aerial_tracking: Path, name: str) -> None:
    sequence = load_sequence(aerial_tracking / name)
    visible = ~np.isnan(sequence.gt).any(axis=1)
    plain = run_job(Job(sequence, TrackerSpec("cv:csrt")))
    fast = run_job(Job(sequence, TrackerSpec("csrt", {"mode": "fast"})))
    plain_iou = iou(plain.boxes[visible], sequence.gt[visible])
    fast_iou = iou(fast.boxes[visible], sequence.gt[visible])
    assert plain.scores.frames_lost == 0 and plain_iou.min() >= MIN_IOU[name] + 0.15  # what justifies the bound
    assert fast.scores.frames_lost == 0
    assert fast_iou.min() >= MIN_IOU[name], f"frame {int(fast_iou.argmin())}: IoU {fast_iou.min():.2f}"
    assert fast_iou.mean() >= plain_iou.mean() - MEAN_GAP[name]
