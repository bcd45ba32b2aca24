"""The reference tracker on real drone video (``shared/data/aerial-tracking``), scored as ``uav-tui eval`` does.

On these two sequences plain OpenCV CSRT never reports a failure and its centre stays within 20 px of
the ground truth on every frame (precision@20px = 1.0), with its IoU never below MIN_IOU_PLAIN. A
tracker that "holds real targets" must do at least as well: report a box on every frame (no false loss)
and keep the IoU of every frame above the same floor. A correctness bound, not a timing one.
"""

from __future__ import annotations

import numpy as np
import pytest

from processors.detection import find_data_dir
from uav_tui.evaluation import Job, TrackerSpec, load_sequence, run_job
from uav_tui.evaluation.metrics import iou

SET = find_data_dir() / "aerial-tracking"

MIN_IOU = {"uav123_10fps-person12_1": 0.3, "uav123_10fps-wakeboard10": 0.1}
"""Per sequence: the lowest per-frame IoU of plain CSRT, rounded down (measured: see the test's assertion)."""


@pytest.mark.skipif(not SET.is_dir(), reason=f"{SET} is not here")
@pytest.mark.parametrize("name", sorted(MIN_IOU))
def test_fast_tracker_holds_the_target_on_every_frame_like_plain_csrt(name: str) -> None:
    sequence = load_sequence(SET / name)
    visible = ~np.isnan(sequence.gt).any(axis=1)
    plain = run_job(Job(sequence, TrackerSpec("cv:csrt")))
    fast = run_job(Job(sequence, TrackerSpec("csrt", {"mode": "fast"})))
    plain_iou = iou(plain.boxes[visible], sequence.gt[visible])
    fast_iou = iou(fast.boxes[visible], sequence.gt[visible])
    assert plain.scores.frames_lost == 0 and plain.scores.precision_20 == 1.0  # what justifies the bound
    assert plain_iou.min() >= MIN_IOU[name]
    assert fast.scores.frames_lost == 0
    assert fast_iou.min() >= MIN_IOU[name], f"frame {int(fast_iou.argmin())}: IoU {fast_iou.min():.2f}"
    assert fast_iou.mean() >= plain_iou.mean() - 0.05
