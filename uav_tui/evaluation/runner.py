"""The one-pass protocol for one sequence x tracker job, and all jobs through :func:`uav_tui.jobs.run_jobs`.

A job starts the processor with ``catch_cmd`` on frame 0's gt box (whole frame pixels), then calls
``photo_processing`` on every frame and reads its ``box`` as the platform does
(:func:`processors.base.read_box`). Only the ``photo_processing`` call is timed; decoding is not,
and frames are decoded one at a time, so a job holds one frame whatever the sequence's length.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from processors.base import read_box
from uav_tui.evaluation.metrics import Scores, score_sequence
from uav_tui.evaluation.sequences import Sequence
from uav_tui.evaluation.trackers import TrackerSpec
from uav_tui.jobs import Progress, run_jobs


@dataclass(frozen=True)
class Job:
    sequence: Sequence
    tracker: TrackerSpec


@dataclass(frozen=True)
class JobResult:
    """What one tracker did on one sequence."""

    sequence: str
    tracker: str
    boxes: np.ndarray
    """``N x 4`` reported boxes, NaN rows where the processor reported none."""
    times_ms: np.ndarray
    """Duration of each ``photo_processing`` call."""
    scores: Scores


def run_job(job: Job) -> JobResult:
    """Run ``job.tracker`` over ``job.sequence`` (one-pass evaluation) and score it."""
    processor = job.tracker.load()
    sequence = job.sequence
    boxes = np.full((len(sequence), 4), np.nan)
    times_ns = np.zeros(len(sequence), np.int64)
    processor.catch_cmd(tuple(int(round(v)) for v in sequence.gt[0]))
    for index, frame in enumerate(sequence.frames()):
        start = time.perf_counter_ns()
        processor.photo_processing(frame)
        times_ns[index] = time.perf_counter_ns() - start
        box = read_box(processor)
        if box is not None:
            boxes[index] = box
    times_ms = times_ns / 1e6
    return JobResult(sequence.name, job.tracker.label, boxes, times_ms, score_sequence(boxes, sequence.gt, times_ms))


def evaluate(sequences: list[Sequence], trackers: list[TrackerSpec], *, workers: int | None = None,
             cluster: str | None = None, progress: Progress | None = None) -> list[JobResult]:
    """Every tracker on every sequence; results in the order sequence-major, tracker-minor."""
    jobs = [Job(sequence, tracker) for sequence in sequences for tracker in trackers]
    return run_jobs(run_job, jobs, workers=workers, cluster=cluster, progress=progress)
