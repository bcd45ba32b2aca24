"""HOTA, IDF1 and MOTA of reported tracks against multi-object ground truth, computed by TrackEval.

The metrics are TrackEval's own (``trackeval.metrics.HOTA``, ``Identity``, ``CLEAR``: the code behind the
MOTChallenge leaderboards), given boxes matched by IoU as its MOTChallenge loader gives them: HOTA over the IoU
thresholds 0.05 .. 0.95, IDF1 and MOTA at IoU 0.5. One frame's boxes are ``(ids, x, y, w, h)``; ids are any integers
(each sequence's are renumbered from 0 here, as TrackEval wants).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from uav_tui.errors import ConfigError

FrameBoxes = tuple[np.ndarray, np.ndarray]
"""One frame: ``ids`` (``K`` integers) and ``boxes`` (``K x 4``, x, y, w, h in pixels)."""


@dataclass(frozen=True)
class MotScores:
    """One tracker's scores on one sequence (or all of them: :func:`combine`)."""

    hota: float
    deta: float
    assa: float
    idf1: float
    mota: float
    id_switches: int
    gt_boxes: int
    reported_boxes: int
    raw: dict[str, dict[str, Any]]
    """TrackEval's results, per metric (what :func:`combine` adds up)."""


def iou_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """IoU of every ``x, y, w, h`` box in ``a`` (rows) with every one in ``b`` (columns)."""
    a, b = a.reshape(-1, 4), b.reshape(-1, 4)
    x1 = np.maximum(a[:, None, 0], b[None, :, 0])
    y1 = np.maximum(a[:, None, 1], b[None, :, 1])
    x2 = np.minimum(a[:, None, 0] + a[:, None, 2], b[None, :, 0] + b[None, :, 2])
    y2 = np.minimum(a[:, None, 1] + a[:, None, 3], b[None, :, 1] + b[None, :, 3])
    inter = np.clip(x2 - x1, 0, None) * np.clip(y2 - y1, 0, None)
    union = (a[:, 2] * a[:, 3])[:, None] + (b[:, 2] * b[:, 3])[None, :] - inter
    return np.where(union > 0, inter / np.where(union > 0, union, 1), 0.0)


def score_tracks(gt: Sequence[FrameBoxes], reported: Sequence[FrameBoxes]) -> MotScores:
    """Score ``reported`` (one entry a frame) against ``gt`` (the same frames)."""
    if len(gt) != len(reported):
        raise ValueError(f"{len(gt)} ground-truth frames but {len(reported)} reported")
    metrics = _metrics()
    data = _trackeval_data(gt, reported)
    return _scores({name: metric.eval_sequence(data) for name, metric in metrics.items()})


def combine(per_sequence: Sequence[MotScores]) -> MotScores:
    """The scores of several sequences together, as TrackEval combines them (counts added, then the ratios)."""
    metrics = _metrics()
    return _scores({name: metric.combine_sequences({str(i): s.raw[name] for i, s in enumerate(per_sequence)})
                    for name, metric in metrics.items()})


def _metrics() -> dict[str, Any]:
    try:  # imported here: its package loads its plotting and datasets too
        from trackeval.metrics import CLEAR, HOTA, Identity
    except ImportError:
        raise ConfigError("multi-object scores need TrackEval: bash scripts/setup.sh dev, or uv pip install "
                          "'uav-tui[mot]' (pip would bring opencv-python too: then run scripts/fix_opencv.sh)",
                          key="mot") from None

    quiet = {"PRINT_CONFIG": False}
    return {"HOTA": HOTA(quiet), "Identity": Identity(quiet), "CLEAR": CLEAR(quiet)}


def _trackeval_data(gt: Sequence[FrameBoxes], reported: Sequence[FrameBoxes]) -> dict[str, Any]:
    """The per-sequence dict TrackEval's metrics take: 0-based ids, an IoU matrix a frame."""
    gt_names = {int(i): n for n, i in enumerate(sorted({int(i) for ids, _ in gt for i in ids}))}
    tr_names = {int(i): n for n, i in enumerate(sorted({int(i) for ids, _ in reported for i in ids}))}
    return {
        "num_timesteps": len(gt),
        "num_gt_ids": len(gt_names), "num_tracker_ids": len(tr_names),
        "num_gt_dets": sum(len(ids) for ids, _ in gt), "num_tracker_dets": sum(len(ids) for ids, _ in reported),
        "gt_ids": [np.array([gt_names[int(i)] for i in ids], np.int64) for ids, _ in gt],
        "tracker_ids": [np.array([tr_names[int(i)] for i in ids], np.int64) for ids, _ in reported],
        "similarity_scores": [iou_matrix(g, r) for (_, g), (_, r) in zip(gt, reported, strict=True)],
    }


def _scores(raw: dict[str, dict[str, Any]]) -> MotScores:
    hota, identity, clear = raw["HOTA"], raw["Identity"], raw["CLEAR"]
    return MotScores(
        hota=float(np.mean(hota["HOTA"])), deta=float(np.mean(hota["DetA"])), assa=float(np.mean(hota["AssA"])),
        idf1=float(identity["IDF1"]), mota=float(clear["MOTA"]), id_switches=int(clear["IDSW"]),
        gt_boxes=int(clear["CLR_TP"] + clear["CLR_FN"]), reported_boxes=int(clear["CLR_TP"] + clear["CLR_FP"]),
        raw=raw)
