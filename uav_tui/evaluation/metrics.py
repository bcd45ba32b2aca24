"""One-pass evaluation metrics (OTB / UAV123 / TrackingNet conventions).

* success: for each IoU threshold t in 0, 0.05, ..., 1 the fraction of frames whose IoU **exceeds**
  t; its mean is the success AUC (a perfect tracker scores 20/21, as IoU 1 never exceeds 1);
* precision: fraction of frames whose centre error is at most d px, d = 0..50; reported at 20 px;
* normalised precision: the centre error divided by the gt box size per axis, thresholds 0..0.5;
  its mean is reported;
* frames lost (lost while visible): frames with a gt box where the tracker reported none (no box scores
  IoU 0 and an infinite centre error);
* absent reported lost: of the frames whose gt is NaN (target not visible), the share where the tracker
  reported no box (what a loss signal is for);
* re-acquired: of the target's reappearances (a visible frame after absent ones), those where the tracker
  reported a box overlapping the gt by IoU :data:`REACQUIRED_IOU` or more within 1 s (the reappearing
  frame and the ``fps - 1`` after it);
* frames to report lost: for each disappearance (an absent frame after a visible one), the frames from the
  first absent one to the first reported lost (the whole absence when none is); their mean.

Frames whose gt is NaN are skipped by every other score. Overall scores average the per-sequence
curves and shares (as the benchmarks' toolkits do) and add up frame counts.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

IOU_THRESHOLDS = np.linspace(0.0, 1.0, 21)
"""Success-plot thresholds."""
PIXEL_THRESHOLDS = np.arange(0, 51, dtype=np.float64)
"""Precision-plot thresholds (centre error, px)."""
NORMALISED_THRESHOLDS = np.linspace(0.0, 0.5, 51)
"""Normalised-precision thresholds (centre error / box size)."""
PRECISION_AT_PX = 20
REACQUIRED_IOU = 0.3
"""Overlap with the gt that counts a reappeared target as found again (half the usual 0.5: a box coming
back onto a target often takes a few frames to fit it)."""


@dataclass(frozen=True)
class Scores:
    """Accuracy and speed of one tracker on one sequence (or, from :func:`summarise`, on all of them)."""

    frames: int
    """Frames processed."""
    scored: int
    """Frames with a gt box."""
    frames_lost: int
    """Lost while visible: frames with a gt box where the tracker reported none."""
    success_auc: float
    precision_20: float
    norm_precision: float
    ms_mean: float
    ms_p50: float
    ms_p95: float
    fps: float
    success_curve: list[float]
    precision_curve: list[float]
    norm_precision_curve: list[float]
    absent_frames: int = 0
    """Frames whose gt is NaN (target not visible)."""
    absent_lost: int = 0
    """Of those, frames where the tracker reported no box."""
    absent_lost_share: float | None = None
    """``absent_lost / absent_frames`` (overall: the mean over the sequences that have absent frames); None
    without absent frames."""

    reappearances: int = 0
    """Visible frames that follow absent ones."""
    reacquired: int = 0
    """Of those, reappearances found again within 1 s (IoU at least :data:`REACQUIRED_IOU`)."""
    disappearances: int = 0
    """Absent frames that follow visible ones."""
    frames_to_lost: float | None = None
    """Mean over the disappearances of the frames until the target was reported lost (the whole absence when
    it was not); None without disappearances."""

    @property
    def reacquired_share(self) -> float | None:
        return self.reacquired / self.reappearances if self.reappearances else None

    def as_dict(self) -> dict:
        return {**asdict(self), "reacquired_share": self.reacquired_share}


def iou(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """Per-row IoU of ``N x 4`` boxes ``x, y, w, h``; 0 where ``pred`` is NaN (no box)."""
    x0 = np.maximum(pred[:, 0], gt[:, 0])
    y0 = np.maximum(pred[:, 1], gt[:, 1])
    x1 = np.minimum(pred[:, 0] + pred[:, 2], gt[:, 0] + gt[:, 2])
    y1 = np.minimum(pred[:, 1] + pred[:, 3], gt[:, 1] + gt[:, 3])
    inter = np.clip(x1 - x0, 0, None) * np.clip(y1 - y0, 0, None)
    union = pred[:, 2] * pred[:, 3] + gt[:, 2] * gt[:, 3] - inter
    with np.errstate(invalid="ignore", divide="ignore"):
        result = inter / union
    return np.nan_to_num(result, nan=0.0)


def centre_error(pred: np.ndarray, gt: np.ndarray, normalised: bool = False) -> np.ndarray:
    """Per-row distance between box centres (px, or in units of the gt box size); inf where ``pred`` is NaN."""
    delta = (pred[:, :2] + pred[:, 2:] / 2) - (gt[:, :2] + gt[:, 2:] / 2)
    if normalised:
        delta = delta / gt[:, 2:]
    error = np.hypot(delta[:, 0], delta[:, 1])
    return np.where(np.isnan(error), np.inf, error)


def score_sequence(pred: np.ndarray, gt: np.ndarray, times_ms: np.ndarray, fps: float = 30.0) -> Scores:
    """Scores of predicted boxes ``pred`` (NaN rows = no box) against ``gt`` (NaN rows skipped); ``fps``: the
    sequence's frames a second (how many frames re-acquisition may take)."""
    visible = ~np.isnan(gt).any(axis=1)
    reappearances, reacquired, disappearances, frames_to_lost = _absences(pred, gt, visible, max(1, round(fps)))
    absent_lost = int((np.isnan(pred).any(axis=1) & ~visible).sum())
    absent = int((~visible).sum())
    pred, gt = pred[visible], gt[visible]
    overlap = iou(pred, gt)
    error = centre_error(pred, gt)
    norm_error = centre_error(pred, gt, normalised=True)
    success = _fractions(overlap, IOU_THRESHOLDS, above=True)
    precision = _fractions(error, PIXEL_THRESHOLDS, above=False)
    norm_precision = _fractions(norm_error, NORMALISED_THRESHOLDS, above=False)
    return Scores(
        frames=len(times_ms), scored=int(visible.sum()), frames_lost=int(np.isnan(pred).any(axis=1).sum()),
        success_auc=float(np.mean(success)), precision_20=float(precision[PRECISION_AT_PX]),
        norm_precision=float(np.mean(norm_precision)), **_timing(times_ms),
        success_curve=success.tolist(), precision_curve=precision.tolist(),
        norm_precision_curve=norm_precision.tolist(), absent_frames=absent, absent_lost=absent_lost,
        absent_lost_share=absent_lost / absent if absent else None, reappearances=reappearances,
        reacquired=reacquired, disappearances=disappearances, frames_to_lost=frames_to_lost,
    )


def summarise(per_sequence: list[Scores], times_ms: np.ndarray) -> Scores:
    """Overall scores: curves averaged over sequences, frame counts added, timing over all frames."""
    curves = {name: np.mean([getattr(s, name) for s in per_sequence], axis=0)
              for name in ("success_curve", "precision_curve", "norm_precision_curve")}
    shares = [s.absent_lost_share for s in per_sequence if s.absent_lost_share is not None]
    disappearances = sum(s.disappearances for s in per_sequence)
    return Scores(
        frames=sum(s.frames for s in per_sequence), scored=sum(s.scored for s in per_sequence),
        frames_lost=sum(s.frames_lost for s in per_sequence),
        success_auc=float(np.mean(curves["success_curve"])),
        precision_20=float(curves["precision_curve"][PRECISION_AT_PX]),
        norm_precision=float(np.mean(curves["norm_precision_curve"])), **_timing(times_ms),
        success_curve=curves["success_curve"].tolist(), precision_curve=curves["precision_curve"].tolist(),
        norm_precision_curve=curves["norm_precision_curve"].tolist(),
        absent_frames=sum(s.absent_frames for s in per_sequence), absent_lost=sum(s.absent_lost for s in per_sequence),
        absent_lost_share=float(np.mean(shares)) if shares else None,
        reappearances=sum(s.reappearances for s in per_sequence), reacquired=sum(s.reacquired for s in per_sequence),
        disappearances=disappearances,
        frames_to_lost=sum((s.frames_to_lost or 0.0) * s.disappearances for s in per_sequence) / disappearances
        if disappearances else None,
    )


def _absences(pred: np.ndarray, gt: np.ndarray, visible: np.ndarray, second: int
              ) -> tuple[int, int, int, float | None]:
    """Reappearances and how many were found again within ``second`` frames; disappearances and the mean frames
    to report each lost."""
    reported = ~np.isnan(pred).any(axis=1)
    change = np.flatnonzero(np.diff(visible.astype(np.int8)))
    gone = [int(i) + 1 for i in change if visible[i]]
    back = [int(i) + 1 for i in change if not visible[i]]
    found = 0
    for start in back:
        window = slice(start, start + second)
        found += bool((iou(pred[window], gt[window]) >= REACQUIRED_IOU).any())
    delays = []
    for start in gone:
        end = next((b for b in back if b > start), len(visible))
        lost = np.flatnonzero(~reported[start:end])
        delays.append(int(lost[0]) if len(lost) else end - start)
    return len(back), found, len(gone), float(np.mean(delays)) if delays else None


def _fractions(values: np.ndarray, thresholds: np.ndarray, *, above: bool) -> np.ndarray:
    if not len(values):
        return np.zeros(len(thresholds))
    hits = values[None, :] > thresholds[:, None] if above else values[None, :] <= thresholds[:, None]
    return hits.mean(axis=1)


def _timing(times_ms: np.ndarray) -> dict[str, float]:
    if not len(times_ms):
        return {"ms_mean": 0.0, "ms_p50": 0.0, "ms_p95": 0.0, "fps": 0.0}
    mean = float(np.mean(times_ms))
    return {"ms_mean": mean, "ms_p50": float(np.percentile(times_ms, 50)),
            "ms_p95": float(np.percentile(times_ms, 95)), "fps": 1000.0 / mean if mean > 0 else 0.0}
