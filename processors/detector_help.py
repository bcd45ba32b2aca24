"""A detector's help for a single-target tracker that has lost its target: candidates of the target's class.

Any tracker can use it: :meth:`DetectorHelp.select` on the operator's selection finds the target's class (the
detection overlapping the selected box best), and while the target is lost :meth:`DetectorHelp.candidates`
gives the detections of that class near where it was last seen, every ``every``-th lost frame. The tracker
checks each against its own appearance of the target before it moves there (:meth:`DetectorHelp.best` does
that with a score it is given). Without a class (no detection overlaps the selection) it gives nothing, and
the tracker's own search stays.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable

import numpy as np

from processors.detection import Backend, DetectorConfig, load_backend
from uav_values.box import Box
from uav_values.detections import Detection

logger = logging.getLogger(__name__)

MIN_WINDOW = 320
"""Shortest side of the window the detector sees (Yolo-Fastest's input): a small target is seen at its size."""


class DetectorHelp:
    """Detections of the selected target's class near where it was lost.

    The detector sees a square window around the box, ``reach`` times its longer side (at least
    :data:`MIN_WINDOW`, at most the frame): a small target far from the camera stays large enough for it, and
    a look-alike across the frame is not offered.

    Args:
        backend: a detector (:func:`processors.detection.load_backend`); None: the shipped Yolo-Fastest.
        every: lost frames between detections (1: every lost frame).
        reach: the window's side in units of the box's longer side.
        min_iou: overlap with the selection a detection needs to give the target's class.
        conf: the shipped detector's confidence threshold (``backend`` keeps its own).
    """

    def __init__(self, backend: Backend | None = None, *, every: int = 2, reach: float = 8.0, min_iou: float = 0.3,
                 conf: float = 0.1) -> None:
        self.backend = backend if backend is not None else load_backend(None, DetectorConfig(conf=conf))
        self.every, self.reach, self.min_iou = max(1, int(every)), reach, min_iou
        self.label: str | None = None
        """The target's class, found at selection; None: no detection overlapped it (no help)."""
        self.ms = 0.0
        """Duration of the last detection (ms): what a lost frame that detects costs."""
        self._lost = 0

    def select(self, frame: np.ndarray, box: Box) -> str | None:
        """Find the target's class: the detection around ``box`` overlapping it best (IoU at least ``min_iou``)."""
        self._lost = 0
        matches = [(iou(d.box, box), d) for d in self._detect(frame, box)]
        overlap, best = max(matches, key=lambda m: m[0], default=(0.0, None))
        self.label = best.label if best is not None and overlap >= self.min_iou else None
        logger.info("DetectorHelp: the target's class is %s (IoU %.2f)", self.label, overlap)
        return self.label

    def found(self) -> None:
        """The tracker has the target again: the next loss counts its lost frames from 0."""
        self._lost = 0

    def candidates(self, frame: np.ndarray, last: Box) -> list[Detection]:
        """On every ``every``-th call (one a lost frame) with a class: the detections of it around ``last``, most
        confident first; else none (and no detection runs)."""
        self._lost += 1
        if self.label is None or self._lost % self.every:
            return []
        return [d for d in self._detect(frame, last) if d.label == self.label]

    def best(self, frame: np.ndarray, last: Box, look: Callable[[Box], float], threshold: float
             ) -> tuple[Box, float] | None:
        """The candidate (:meth:`candidates`) whose appearance ``look(box)`` is highest, when at least
        ``threshold``: the box and its look; None when no candidate looks like the target."""
        scored = [(look(d.box), d.box) for d in self.candidates(frame, last)]
        score, box = max(scored, key=lambda s: s[0], default=(-1.0, last))
        return (box, score) if scored and score >= threshold else None

    def _detect(self, frame: np.ndarray, box: Box) -> list[Detection]:
        """Detections in the window around ``box``, in frame pixels."""
        height, width = frame.shape[:2]
        side = min(max(MIN_WINDOW, self.reach * max(box[2], box[3])), width, height)
        cx, cy = box[0] + box[2] / 2, box[1] + box[3] / 2
        x0 = int(max(0, min(cx - side / 2, width - side)))
        y0 = int(max(0, min(cy - side / 2, height - side)))
        started = time.perf_counter()
        found = self.backend.detect(frame[y0:y0 + int(side), x0:x0 + int(side)])
        self.ms = (time.perf_counter() - started) * 1e3
        return [dataclasses.replace(d, box=(d.box[0] + x0, d.box[1] + y0, d.box[2], d.box[3])) for d in found]


def iou(a: Box, b: Box) -> float:
    """Overlap of two ``x, y, w, h`` boxes (intersection over union)."""
    x0, y0 = max(a[0], b[0]), max(a[1], b[1])
    x1, y1 = min(a[0] + a[2], b[0] + b[2]), min(a[1] + a[3], b[1] + b[3])
    inter = max(0.0, x1 - x0) * max(0.0, y1 - y0)
    union = a[2] * a[3] + b[2] * b[3] - inter
    return inter / union if union > 0 else 0.0
