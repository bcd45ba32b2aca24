"""The one-pass protocol for one sequence x tracker job, and all jobs through :func:`uav_tui.evaluation.jobs.run_jobs`.

A job starts the processor with ``catch_cmd`` on frame 1's gt box (whole frame pixels), then calls
``photo_processing`` on every frame and reads its ``box`` as the platform does
(:func:`uav_tui.hosting.frame_call.call_frame`, the call every host makes). Only the ``photo_processing``
call is timed; decoding is not, and frames are decoded one at a time, so a job holds one frame whatever the
sequence's length.

The processor's ``tmMgr`` is a :class:`~processors.frame_telemetry.FrameTelemetry`, as in a run: its
snapshot has no vehicle (every telemetry field None) and the frame's number and time in the sequence;
its saves go to the job's folder (:class:`SaveFolder`), at most :data:`SAVE_CAP` images a job.

A processor that raises (loading, in ``catch_cmd`` or on a frame) fails its job alone: the result says
where and why, and has no scores.
"""

from __future__ import annotations

import json
import os
import traceback
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from controllers.base import TELEMETRY_FIELDS
from processors.detection.onnx_runtime import THREADS_ENV
from processors.frame_telemetry import FrameTelemetry
from uav_tui.evaluation.jobs import Progress, run_jobs
from uav_tui.evaluation.metrics import Scores, score_sequence
from uav_tui.evaluation.sequences import Sequence
from uav_tui.evaluation.trackers import TrackerSpec
from uav_tui.hosting.frame_call import call_frame, describe
from uav_tui.recording.rows import extra_json

NO_VEHICLE = {name: None for name in TELEMETRY_FIELDS if name != "heartbeat_age_s"}
"""The telemetry of every eval frame: there is no vehicle."""
SAVE_CAP = 100
"""Images a job stores from ``tmMgr.save``; later saves are counted, not stored."""


@dataclass(frozen=True)
class Job:
    sequence: Sequence
    tracker: TrackerSpec
    threads: int = 1
    """OpenCV and ONNX Runtime threads of the job (1: timings compare across trackers and workers)."""
    saves_dir: Path | None = None
    """Where ``tmMgr.save`` stores images (None: counted only)."""


@dataclass(frozen=True)
class JobResult:
    """What one tracker did on one sequence."""

    sequence: str
    tracker: str
    boxes: np.ndarray
    """``N x 4`` reported boxes, NaN rows where the processor reported none (or had not got to)."""
    times_ms: np.ndarray
    """Duration of each ``photo_processing`` call (of those made)."""
    scores: Scores | None
    """None when the job failed."""
    error: str | None = None
    """Why it failed: ``ValueError: text (file.py:12)``; None when it did not."""
    failed_at: str = ""
    """Where: ``loading``, ``catch_cmd`` (given frame 1's box) or ``frame 5`` (1 = the first frame)."""
    traceback: str = ""
    saves: int = 0
    """``tmMgr.save`` images stored."""
    save_calls: int = 0
    """``tmMgr.save`` calls made (stored, over the cap, or above ``save_max_hz``)."""
    threads: int = 1

    @property
    def failed(self) -> bool:
        return self.error is not None

    @property
    def key(self) -> tuple[str, str]:
        return self.sequence, self.tracker


class SaveFolder:
    """``tmMgr.save`` in eval: images and fields queued during the timed call, written after it.

    ``folder/NNNNNN.jpg`` (the frame's number) and one JSON line a save in ``folder/saves.jsonl``; at most
    ``cap`` images, the rest counted.
    """

    def __init__(self, folder: Path | None, cap: int = SAVE_CAP) -> None:
        self.folder, self.cap = folder, cap
        self.stored = 0
        self._queued: list[tuple[np.ndarray, dict[str, Any]]] = []

    def keep(self, image: np.ndarray, extra: dict[str, Any]) -> None:
        if self.folder is not None and self.stored + len(self._queued) < self.cap:
            self._queued.append((np.array(image), extra))

    def write(self, frame: int, t_s: float) -> None:
        """Write what was saved during frame ``frame``."""
        if not self._queued or self.folder is None:
            return
        self.folder.mkdir(parents=True, exist_ok=True)
        with open(self.folder / "saves.jsonl", "a") as lines:
            for number, (image, extra) in enumerate(self._queued):
                name = f"{frame:06d}.jpg" if number == 0 else f"{frame:06d}-{number}.jpg"
                cv2.imwrite(str(self.folder / name), image)
                head = json.dumps({"frame": frame, "t_s": round(t_s, 6), "image": name})[:-1]
                lines.write(f'{head}, "extra": {extra_json(extra) or "{}"}}}\n')
                self.stored += 1
        self._queued = []


def set_threads(threads: int) -> None:
    """OpenCV's and ONNX Runtime's threads in this process (ONNX sessions made after this call)."""
    cv2.setNumThreads(threads)
    os.environ[THREADS_ENV] = str(threads)


class _Failed(Exception):
    """A frame on which the processor raised: the exception in one line, and its traceback."""

    def __init__(self, raised: str, traceback_text: str) -> None:
        super().__init__(raised)
        self.raised, self.traceback = raised, traceback_text


def run_job(job: Job) -> JobResult:
    """Run ``job.tracker`` over ``job.sequence`` (one-pass evaluation) and score it; never raises for the processor."""
    set_threads(job.threads)
    sequence = job.sequence
    boxes = np.full((len(sequence), 4), np.nan)
    times_ns = np.zeros(len(sequence), np.int64)
    folder = SaveFolder(job.saves_dir)
    telemetry = FrameTelemetry(folder.keep)
    stage, made = "loading", 0
    try:
        processor = job.tracker.load()
        processor.tmMgr = telemetry
        stage = "catch_cmd"
        telemetry.begin(1, 0, 0, NO_VEHICLE, None)
        processor.catch_cmd(tuple(int(round(v)) for v in sequence.gt[0]))
        for index, image in enumerate(sequence.frames()):
            frame = index + 1
            stage = f"frame {frame}"
            t_ns = round(index * 1e9 / sequence.fps)
            telemetry.begin(frame, t_ns, 0, NO_VEHICLE, None)
            outcome = call_frame(processor, image, vector=False)
            if outcome.error is not None:
                raise _Failed(outcome.raised, outcome.error)
            times_ns[index] = outcome.t_end_ns - outcome.t_start_ns
            made = frame
            if outcome.box is not None:
                boxes[index] = outcome.box
            folder.write(frame, t_ns / 1e9)
    except Exception as exc:  # noqa: BLE001 - the job fails alone, saying where and why
        failed = exc if isinstance(exc, _Failed) else _Failed(describe(exc), traceback.format_exc())
        return JobResult(sequence.name, job.tracker.label, boxes, times_ns[:made] / 1e6, None,
                         error=failed.raised, failed_at=stage, traceback=failed.traceback,
                         saves=folder.stored, save_calls=telemetry.saves + telemetry.saves_throttled,
                         threads=job.threads)
    times_ms = times_ns / 1e6
    scores = score_sequence(boxes, sequence.gt, times_ms, sequence.fps)
    return JobResult(sequence.name, job.tracker.label, boxes, times_ms, scores,
                     saves=folder.stored, save_calls=telemetry.saves + telemetry.saves_throttled, threads=job.threads)


def evaluate(sequences: list[Sequence], trackers: list[TrackerSpec], *, workers: int | None = None,
             cluster: str | None = None, progress: Progress | None = None, threads: int = 1,
             saves_dir: Path | None = None, done: Iterable[JobResult] = (),
             on_result: Callable[[JobResult], None] | None = None) -> list[JobResult]:
    """Every tracker on every sequence; results in the order sequence-major, tracker-minor.

    Args:
        threads: OpenCV / ONNX Runtime threads per job.
        saves_dir: ``tmMgr.save`` images go to ``saves_dir/<tracker>/<sequence>/`` (None: counted only).
        done: results of jobs already run (``--resume``): these jobs are not run again.
        on_result: given each new result as its job finishes.
        progress: ``progress(done, total)``, counting ``done`` as finished.
    """
    finished = {result.key: result for result in done}
    jobs = [Job(sequence, tracker, threads, saves_dir / _slug(tracker.label) / sequence.name if saves_dir else None)
            for sequence in sequences for tracker in trackers]
    todo = [job for job in jobs if (job.sequence.name, job.tracker.label) not in finished]
    skipped = len(jobs) - len(todo)

    def report(index: int, result: JobResult) -> None:
        finished[result.key] = result
        if on_result:
            on_result(result)

    run_jobs(run_job, todo, workers=workers, cluster=cluster, on_result=report,
             progress=(lambda count, total: progress(skipped + count, len(jobs))) if progress else None)
    return [finished[(job.sequence.name, job.tracker.label)] for job in jobs]


def _slug(label: str) -> str:
    """A tracker label as one folder name."""
    return "".join(c if c.isalnum() or c in "._=-" else "_" for c in label)[:100] or "tracker"
