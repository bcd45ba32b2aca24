"""``uav-tui eval``: score processors on annotated video, as single-object tracking papers do.

* :mod:`.sequences` finds and reads annotated sequences (``video.mp4`` + ``gt.txt``, or OTB/UAV123 images);
* :mod:`.trackers` names what is scored (any processor with ``catch_cmd`` and ``box``, or ``cv:NAME``);
* :mod:`.metrics` turns boxes into success / precision curves;
* :mod:`.runner` runs one sequence x tracker job (one-pass protocol) and all jobs through :mod:`.jobs`;
* :mod:`.report` prints the table and writes the JSON and the plots;
* :mod:`.journal` appends each finished job to ``jobs.jsonl`` and reads them back for ``--resume``;
* ``--mot``: :mod:`.mot_sequences` reads MOTChallenge-layout sequences, :mod:`.mot_runner` tracks a processor's
  detections the platform's way and ByteTrack's, :mod:`.mot_metrics` scores them (TrackEval), :mod:`.mot_cli`
  reports.
"""

from __future__ import annotations

from uav_tui.evaluation import journal
from uav_tui.evaluation.metrics import Scores, score_sequence, summarise
from uav_tui.evaluation.runner import Job, JobResult, evaluate, run_job
from uav_tui.evaluation.sequences import Sequence, SequenceError, find_sequences, load_sequence
from uav_tui.evaluation.trackers import TrackerSpec

__all__ = [
    "Job", "JobResult", "Scores", "Sequence", "SequenceError", "TrackerSpec", "evaluate", "find_sequences",
    "journal", "load_sequence", "run_job", "score_sequence", "summarise",
]
