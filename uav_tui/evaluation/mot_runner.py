"""One multi-object job: a detecting processor over a sequence, its detections tracked two ways, both scored.

Each frame goes through the processor as every host sends it (:func:`uav_tui.hosting.frame_call.call_frame`); its
checked ``detections`` are then given, in frame order and stamped with the frame's time in the sequence, to

* ``platform``: :class:`uav_tui.hosting.tracks.DetectionTracks`, the tracks a flight records and shows;
* ``bytetrack``: the same library's ``ByteTrack()`` with its defaults, the baseline.

A detection without a track (ByteTrack's first low-score sighting) is not reported. Each tracker's reports are kept
to the scored classes and cleared of the ignored boxes (:mod:`.mot_sequences`), then scored
(:func:`.mot_metrics.score_tracks`). The processor's ``photo_processing`` (which holds its detector) and each
tracker's update are timed apart, so the trackers' cost compares with the detector's.
"""

from __future__ import annotations

import time
import zlib
from dataclasses import dataclass, field
from typing import Any

import cv2
import numpy as np
from edgefirst.tracker import ByteTrack

from processors import load_processor
from uav_tui.evaluation.mot_metrics import FrameBoxes, MotScores, iou_matrix, score_tracks
from uav_tui.evaluation.mot_sequences import SCORED_LABELS, MotSequence
from uav_tui.evaluation.runner import set_threads
from uav_tui.hosting.frame_call import call_frame
from uav_tui.hosting.tracks import DetectionTracks
from uav_values.detections import Detected

TRACKERS = ("platform", "bytetrack")
IGNORE_IOU = 0.5
"""A report covering an ignored box at least this much (and more than any scored one) is not counted."""

Reported = list[tuple[int, tuple[float, float, float, float], str]]
"""One frame's reports: ``(track id, x, y, w, h, label)``."""


@dataclass(frozen=True)
class MotJob:
    sequence: MotSequence
    processor: str = "yolo"
    kwargs: dict[str, Any] = field(default_factory=dict)
    threads: int = 1

    @property
    def label(self) -> str:
        return " ".join([self.processor, *(f"{key}={value}" for key, value in self.kwargs.items())])


@dataclass(frozen=True)
class MotResult:
    sequence: str
    processor: str
    frames: int
    scores: dict[str, MotScores]
    """Per tracker (:data:`TRACKERS`); empty when the job failed."""
    ms: dict[str, np.ndarray]
    """Per frame: ``detector`` (``photo_processing``) and each tracker's update."""
    error: str | None = None


class _ByteTrackDefaults:
    """``ByteTrack()`` as the library makes it, its UUIDs numbered in order of appearance."""

    def __init__(self) -> None:
        self._tracker = ByteTrack()
        self._ids: dict[str, int] = {}

    def assign(self, found: tuple[Detected, ...], at_ns: int) -> list[int | None]:
        boxes = np.array([(x, y, x + w, y + h) for (x, y, w, h) in (d.box for d in found)], np.float32).reshape(-1, 4)
        scores = np.array([d.score for d in found], np.float32)
        labels = np.array([zlib.crc32(d.label.encode()) for d in found], np.uint64)
        tracks = self._tracker.update(boxes, scores, labels, at_ns)
        return [None if t is None else self._ids.setdefault(t.uuid, len(self._ids)) for t in tracks]


def run_mot_job(job: MotJob) -> MotResult:
    """Run ``job`` and score both trackers; a processor that raises fails the job (the result says where and why)."""
    set_threads(job.threads)
    sequence = job.sequence
    ms = {name: np.zeros(len(sequence)) for name in ("detector", *TRACKERS)}
    reported: dict[str, list[FrameBoxes]] = {name: [] for name in TRACKERS}
    processor = load_processor(job.processor, dict(job.kwargs)).instance
    platform, baseline = DetectionTracks(), _ByteTrackDefaults()
    for index, path in enumerate(sequence.images):
        image = cv2.imread(str(path), cv2.IMREAD_COLOR)
        outcome = call_frame(processor, image, vector=False)
        if outcome.error is not None:
            return MotResult(sequence.name, job.label, index, {}, ms, f"frame {index + 1}: {outcome.raised}")
        ms["detector"][index] = (outcome.t_end_ns - outcome.t_start_ns) / 1e6
        found, at_ns = outcome.detections or (), round(index * 1e9 / sequence.fps)
        start = time.perf_counter_ns()
        tracked = platform.assign(found, at_ns) or ()
        middle = time.perf_counter_ns()
        baseline_ids = baseline.assign(found, at_ns)
        ms["platform"][index], ms["bytetrack"][index] = (middle - start) / 1e6, (time.perf_counter_ns() - middle) / 1e6
        ignored = sequence.ignored(index + 1)
        _, gt_boxes = sequence.scored(index + 1)
        reported["platform"].append(_counted([(d.track_id, d.box, d.label) for d in tracked], gt_boxes, ignored))
        reported["bytetrack"].append(_counted([(i, d.box, d.label) for i, d in zip(baseline_ids, found, strict=True)],
                                              gt_boxes, ignored))
    gt = [sequence.scored(frame) for frame in range(1, len(sequence) + 1)]
    return MotResult(sequence.name, job.label, len(sequence),
                     {name: score_tracks(gt, reported[name]) for name in TRACKERS}, ms)


def _counted(reports: list[tuple[int | None, Any, str]], gt_boxes: np.ndarray, ignored: np.ndarray) -> FrameBoxes:
    """The tracked reports of a scored class that cover no ignored box more than a scored one."""
    kept = [(i, box) for i, box, label in reports if i is not None and label in SCORED_LABELS]
    if not kept:
        return np.zeros(0, np.int64), np.zeros((0, 4))
    ids = np.array([i for i, _ in kept], np.int64)
    boxes = np.array([box for _, box in kept], np.float64).reshape(-1, 4)
    if len(ignored):
        on_ignored = iou_matrix(boxes, ignored).max(axis=1)
        on_scored = iou_matrix(boxes, gt_boxes).max(axis=1) if len(gt_boxes) else np.zeros(len(boxes))
        keep = ~((on_ignored >= IGNORE_IOU) & (on_ignored > on_scored))
        ids, boxes = ids[keep], boxes[keep]
    return ids, boxes
