"""``jobs.jsonl``: every finished job's boxes and times, one JSON line each, appended as it finishes.

It is what ``--resume DIR`` reads back: the finished jobs are scored again from their boxes (against the
sequence's gt as it is now) and not run again; failed jobs run again. A line cut short by a crash is ignored.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from uav_tui.evaluation.metrics import score_sequence
from uav_tui.evaluation.runner import JobResult
from uav_tui.evaluation.sequences import Sequence, SequenceError

JOURNAL = "jobs.jsonl"


def append(folder: Path, result: JobResult) -> None:
    """Add ``result`` to ``folder/jobs.jsonl`` and make it durable (a crash right after keeps it)."""
    line = json.dumps({
        "sequence": result.sequence, "tracker": result.tracker, "threads": result.threads,
        "boxes": [None if math.isnan(row[0]) else [float(v) for v in row] for row in result.boxes],
        "times_ms": [round(float(t), 4) for t in result.times_ms], "error": result.error,
        "failed_at": result.failed_at, "traceback": result.traceback, "saves": result.saves,
        "save_calls": result.save_calls,
    }, allow_nan=False)
    with open(folder / JOURNAL, "a") as handle:
        handle.write(line + "\n")
        handle.flush()
        os.fsync(handle.fileno())


def read(folder: Path, sequences: list[Sequence], threads: int) -> list[JobResult]:
    """The jobs that finished without failing in an earlier run into ``folder``, on sequences of ``sequences``.

    Raises:
        SequenceError: ``folder`` holds no journal, or its jobs ran with another ``--threads``.
    """
    path = folder / JOURNAL
    if not path.is_file():
        raise SequenceError(f"--resume {folder}: there is no {JOURNAL} in it; give the --out folder of an earlier "
                            "uav-tui eval")
    by_name = {sequence.name: sequence for sequence in sequences}
    results: dict[tuple[str, str], JobResult] = {}
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        try:
            entry: dict[str, Any] = json.loads(line)
        except ValueError:
            continue  # the last line of a run killed while writing it
        sequence = by_name.get(entry.get("sequence", ""))
        if entry.get("threads") != threads:
            raise SequenceError(f"{path}:{number}: that job ran with --threads {entry.get('threads')}; resume with "
                                "the same --threads, so that timings compare")
        if sequence is None or entry.get("error") or len(entry["boxes"]) != len(sequence):
            results.pop((entry.get("sequence", ""), entry.get("tracker", "")), None)
            continue
        boxes = np.array([row if row is not None else [math.nan] * 4 for row in entry["boxes"]], np.float64)
        times_ms = np.array(entry["times_ms"], np.float64)
        result = JobResult(sequence.name, entry["tracker"], boxes.reshape(-1, 4), times_ms,
                           score_sequence(boxes.reshape(-1, 4), sequence.gt, times_ms, sequence.fps),
                           saves=entry["saves"], save_calls=entry["save_calls"], threads=threads)
        results[result.key] = result
    return list(results.values())
