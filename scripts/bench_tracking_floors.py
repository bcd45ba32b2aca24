"""How far issue 37's tracker goals can be reached at all: CSRT's speed/accuracy front and NanoTrack's loss bound.

    .venv/bin/python scripts/bench_tracking_floors.py [--data DIR] [--part csrt|oracle|both]

Both parts run plain OpenCV trackers (one thread) one-pass on every sequence of the development set and score
them as ``uav-tui eval`` does (success AUC averaged over sequences; ``even``/``odd``: the sequences at even or
odd positions in name order, the halves a setting must win on):

* ``csrt``: ``cv2.TrackerCSRT`` with OpenCV's defaults (``cv:csrt``) and with each setting of
  :data:`CSRT_SETTINGS` (its speed knobs; ``psr_threshold`` 0, so it never gives up on its own). Cost is
  thread CPU ms per ``update``: a ratio that holds on a loaded machine, unlike wall time. Each row says
  whether it is on the AUC/CPU Pareto front, and ``meets_goal`` names the settings with AUC >= the
  defaults' at <= 0.5x their CPU;
* ``oracle``: ``cv2.TrackerNano`` (``cv:nano``) alone, and with a perfect loss signal and re-acquisition: no
  box exactly on the absent-target frames (gt ``NaN``), and on a visible frame where its box misses the target
  (IoU 0, scored as such) it restarts on the gt box with the template it was selected with (pasted there:
  :class:`SelectedTemplate`). The AUC gained is the most any loss logic on
  top of NanoTrack could gain (the tracker itself unchanged).

Prints one JSON object.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from processors.models import create_nanotrack  # noqa: E402
from uav_tui.errors import ConfigError  # noqa: E402
from uav_tui.evaluation import Scores, Sequence, find_sequences, score_sequence, summarise  # noqa: E402
from uav_tui.evaluation.metrics import iou  # noqa: E402
from uav_tui.evaluation.sequences import aerial_tracking_set  # noqa: E402

FAST = {"template_size": 128, "use_segmentation": False, "psr_threshold": 0.0}
"""The OpenCV part of ``csrt`` mode fast."""

CSRT_SETTINGS: list[dict[str, Any]] = [
    FAST,
    {**FAST, "template_size": 96},
    {**FAST, "template_size": 64},
    {**FAST, "use_color_names": False},
    {**FAST, "template_size": 96, "use_color_names": False, "number_of_scales": 17, "admm_iterations": 3},
]
"""CSRT settings tried beside OpenCV's defaults: mode fast's, smaller templates, no colour names, and the cheapest
combination of knobs (earlier sessions found 2-3 ADMM iterations, 25 scales, a 256-px scale model or 9 HOG channels
saved at most 0.07x each)."""


def csrt_run(sequences: list[Sequence], setting: dict[str, Any]) -> tuple[list[Scores], float]:
    """Per-sequence scores of CSRT with ``setting`` and its mean thread CPU ms an ``update``."""
    per, cpu = [], []
    for sequence in sequences:
        boxes = []
        for index, frame in enumerate(sequence.frames()):
            if index == 0:
                tracker = _csrt(setting)
                tracker.init(frame, tuple(int(round(v)) for v in sequence.gt[0]))
                boxes.append(sequence.gt[0])
                continue
            start = time.thread_time()
            ok, box = tracker.update(frame)
            cpu.append(time.thread_time() - start)
            boxes.append(box if ok else [np.nan] * 4)
        per.append(score_sequence(np.array(boxes, float), sequence.gt, np.ones(1)))
    return per, 1e3 * float(np.mean(cpu))


def exemplar_side(w: float, h: float) -> int:
    """Side of the square NanoTrack cuts its template from: the box with half its perimeter as context."""
    context = 0.5 * (w + h)
    return max(int(math.sqrt((w + context) * (h + context))), 1)


class SelectedTemplate:
    """The square of the frame around the selected target that ``cv2.TrackerNano.init`` turns into its template.

    ``cv2.TrackerNano`` takes its template from the image it is started on: :meth:`pasted` puts this square
    (resized) where a NanoTrack started on another box cuts its template from, so the new tracker looks for the
    target *as it was selected*.
    """

    def __init__(self, frame: np.ndarray, box: tuple[float, ...]) -> None:
        x, y, w, h = box
        side = exemplar_side(w, h)
        self.view = cv2.getRectSubPix(frame, (side, side), (x + w / 2, y + h / 2))
        """The selected target with its context (replicated past the frame's edges)."""

    def pasted(self, frame: np.ndarray, box: tuple[float, ...]) -> np.ndarray:
        """A copy of ``frame`` with the selected view (resized to ``box``'s) where a NanoTrack started on ``box``
        cuts its template from."""
        x, y, w, h = box
        side = exemplar_side(w, h)
        patch = cv2.resize(self.view, (side, side), interpolation=cv2.INTER_AREA)
        image = frame.copy()
        x0, y0 = int(x + w / 2) - (side + 1) // 2, int(y + h / 2) - (side + 1) // 2  # where init will cut it from
        ix0, iy0 = max(x0, 0), max(y0, 0)
        ix1, iy1 = min(x0 + side, image.shape[1]), min(y0 + side, image.shape[0])
        if ix1 > ix0 and iy1 > iy0:
            image[iy0:iy1, ix0:ix1] = patch[iy0 - y0 : iy1 - y0, ix0 - x0 : ix1 - x0]
        return image


def nano_run(sequence: Sequence, oracle: bool) -> Scores:
    """NanoTrack on ``sequence``; with ``oracle``, no box on absent frames and a restart on gt where it misses."""
    boxes: list[Any] = []
    for index, frame in enumerate(sequence.frames()):
        truth = sequence.gt[index]
        if index == 0:
            selected = SelectedTemplate(frame, tuple(truth))
            tracker = create_nanotrack()
            tracker.init(frame, tuple(int(round(v)) for v in truth))
            boxes.append(truth)
            continue
        _, box = tracker.update(frame)
        found = np.array(box, float)
        if oracle and np.isnan(truth).any():
            found = np.full(4, np.nan)
        elif oracle and iou(found[None], truth[None])[0] <= 0:
            tracker = create_nanotrack()
            tracker.init(selected.pasted(frame, tuple(truth)), tuple(int(round(v)) for v in truth))
        boxes.append(found)
    return score_sequence(np.array(boxes, float), sequence.gt, np.ones(1))


def overall(per: list[Scores]) -> dict[str, Any]:
    """AUC over all sequences and over each half; precision@20 and the absent share over all."""
    def auc(part: list[Scores]) -> float | None:
        return round(summarise(part, np.ones(1)).success_auc, 4) if part else None
    whole = summarise(per, np.ones(1))
    return {"auc": auc(per), "auc_even": auc(per[0::2]), "auc_odd": auc(per[1::2]),
            "precision_20": round(whole.precision_20, 4), "lost_while_visible": whole.frames_lost,
            "absent_reported_lost_share": whole.absent_lost_share}


def csrt_front(sequences: list[Sequence]) -> dict[str, Any]:
    """Every CSRT setting's scores and CPU against OpenCV's defaults, the Pareto front, and the goal's verdict."""
    per, base_ms = csrt_run(sequences, {})
    base = {**overall(per), "cpu_ms": round(base_ms, 2)}
    rows = []
    for setting in CSRT_SETTINGS:
        per, ms = csrt_run(sequences, setting)
        rows.append({"setting": setting, **overall(per), "cpu_ms": round(ms, 2), "cpu_ratio": round(ms / base_ms, 3)})
    return {"defaults": base, **front(base, rows)}


def front(base: dict[str, Any], rows: list[dict[str, Any]]) -> dict[str, Any]:
    """``rows`` each marked ``pareto`` (no other row has at least its AUC at at most its CPU, one of them
    strictly), the settings that meet the goal (AUC >= ``base``'s at <= 0.5x its CPU), the best AUC at <= 0.5x."""
    def beaten(row: dict[str, Any]) -> bool:
        return any(other["auc"] >= row["auc"] and other["cpu_ms"] <= row["cpu_ms"]
                   and (other["auc"], other["cpu_ms"]) != (row["auc"], row["cpu_ms"]) for other in rows)
    marked = [{**row, "pareto": not beaten(row)} for row in rows]
    half = [row for row in marked if row["cpu_ms"] <= 0.5 * base["cpu_ms"]]
    return {"settings": marked, "meets_goal": [row["setting"] for row in half if row["auc"] >= base["auc"]],
            "best_auc_at_half_cpu": max((row["auc"] for row in half), default=None)}


def nano_bound(sequences: list[Sequence]) -> dict[str, Any]:
    """cv:nano alone and with the oracle: what a perfect loss signal and re-acquisition would add."""
    plain = overall([nano_run(s, oracle=False) for s in sequences])
    perfect = overall([nano_run(s, oracle=True) for s in sequences])
    return {"cv:nano": plain, "oracle": perfect, "oracle_gain": round(perfect["auc"] - plain["auc"], 4)}


def _csrt(knobs: dict[str, Any]) -> cv2.TrackerCSRT:
    params = cv2.TrackerCSRT.Params()
    for key, value in knobs.items():
        setattr(params, key, value)
    return cv2.TrackerCSRT.create(params)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, help="the sequences (default: the aerial-tracking set where the "
                        "tests find it)")
    parser.add_argument("--part", choices=("csrt", "oracle", "both"), default="both")
    args = parser.parse_args()
    cv2.setNumThreads(1)
    try:
        args.data = args.data or aerial_tracking_set()
    except ConfigError as exc:
        parser.error(str(exc))
    sequences = find_sequences([args.data])
    document: dict[str, Any] = {"data": str(args.data), "sequences": len(sequences), "threads": 1}
    if args.part in ("csrt", "both"):
        document["csrt"] = csrt_front(sequences)
    if args.part in ("oracle", "both"):
        document["nanotrack_oracle"] = nano_bound(sequences)
    print(json.dumps(document, indent=1))


if __name__ == "__main__":
    main()
