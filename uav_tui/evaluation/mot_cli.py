"""``uav-tui eval --mot``: multi-object tracking scores of a detecting processor's tracks; table and ``mot.json``."""

from __future__ import annotations

import argparse
import datetime
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table

from processors import load_processor
from processors.detection import DATA_DIR_ENV
from uav_tui.arguments import ArgumentParser
from uav_tui.config import parse_processor_args
from uav_tui.errors import KNOWN_ERRORS
from uav_tui.evaluation.jobs import run_jobs
from uav_tui.evaluation.mot_metrics import MotScores, combine
from uav_tui.evaluation.mot_runner import TRACKERS, MotJob, MotResult, run_mot_job
from uav_tui.evaluation.mot_sequences import MOT_SET, aerial_mot_set, find_mot_sequences
from uav_tui.output.text import safe

RESULTS = "mot.json"


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(
        prog="uav-tui eval --mot",
        description="Score multi-object tracking: a detecting processor over MOTChallenge-layout sequences, its "
                    "detections tracked by the platform (as in a flight) and by ByteTrack with the library's "
                    "defaults; HOTA, IDF1, MOTA (TrackEval) and each one's cost a frame beside the detector's.")
    parser.add_argument("data", nargs="*", type=Path, help=f"a sequence folder (img1/, gt/gt.txt, seqinfo.ini) or "
                        f"a folder of them (default: the {MOT_SET} set in ${DATA_DIR_ENV}, else in shared/data "
                        "beside the repository)")
    parser.add_argument("--processor", "-p", default="yolo", metavar="SPEC",
                        help="the detecting processor, as for a run (default: yolo)")
    parser.add_argument("--processor-arg", action="append", default=[], metavar="KEY=VALUE",
                        help="its constructor argument (a TOML literal); repeat")
    parser.add_argument("--workers", type=int, metavar="N", help="local worker processes (default: one per core; "
                        "1 to compare milliseconds)")
    parser.add_argument("--threads", type=int, default=1, metavar="N", help="OpenCV threads of each job (default 1)")
    parser.add_argument("--out", type=Path, metavar="DIR", help=f"where {RESULTS} goes (default: "
                        "eval-results/<UTC time>-mot)")
    return parser


def main(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    console = Console(highlight=False, width=None if sys.stdout.isatty() else 160)
    try:
        kwargs = parse_processor_args(args.processor_arg)
        load_processor(args.processor, dict(kwargs))  # a wrong name or argument fails here, before any job starts
        sequences = find_mot_sequences(args.data or [aerial_mot_set()])
        jobs = [MotJob(sequence, args.processor, kwargs, args.threads) for sequence in sequences]
        results = run_jobs(run_mot_job, jobs, workers=args.workers)
    except KNOWN_ERRORS as exc:
        print(f"uav-tui eval --mot: {safe(str(exc))}", file=sys.stderr)
        return 2
    out = args.out or Path("eval-results") / (datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H-%M-%SZ")
                                              + "-mot")
    out.mkdir(parents=True, exist_ok=True)
    summary = summarise(results, [str(p) for p in args.data])
    (out / RESULTS).write_text(json.dumps(summary, indent=2) + "\n")
    console.print(table(summary))
    for result in results:
        if result.error:
            console.print(f"[red]{safe(result.sequence)}: {safe(result.error)}[/red]")
    console.print(f"wrote {out / RESULTS}")
    return 1 if any(result.error for result in results) else 0


def summarise(results: list[MotResult], sources: list[str]) -> dict[str, Any]:
    """Per sequence and overall: each tracker's scores, and the detector's and each tracker's milliseconds a frame."""
    done = [result for result in results if result.error is None]
    return {
        "data": sources, "processor": results[0].processor if results else None,
        "sequences": {r.sequence: {"frames": r.frames, "error": r.error,
                                   "scores": {name: _row(s) for name, s in r.scores.items()},
                                   "ms_per_frame": _ms(r.ms)} for r in results},
        "overall": {"frames": sum(r.frames for r in done),
                    "scores": {name: _row(combine([r.scores[name] for r in done])) for name in TRACKERS} if done
                    else {},
                    "ms_per_frame": _ms({k: np.concatenate([r.ms[k] for r in done]) for k in done[0].ms}) if done
                    else {}},
    }


def table(summary: dict[str, Any]) -> Table:
    view = Table(title=f"multi-object tracking: {summary['processor']}'s detections")
    for column in ("sequence", "tracker", "HOTA", "DetA", "AssA", "IDF1", "MOTA", "IDSW", "ms/frame", "of detector"):
        view.add_column(column, justify="left" if column in ("sequence", "tracker") else "right")
    rows = [*summary["sequences"].items(), ("overall", summary["overall"])]
    for name, entry in rows:
        detector = entry["ms_per_frame"].get("detector", {}).get("mean")
        for tracker, scores in entry["scores"].items():
            ms = entry["ms_per_frame"][tracker]["mean"]
            view.add_row(name, tracker, *(f"{scores[key]:.3f}" for key in ("hota", "deta", "assa", "idf1", "mota")),
                         str(scores["id_switches"]), f"{ms:.3f}", f"{ms / detector:.1%}" if detector else "-")
    return view


def _row(scores: MotScores) -> dict[str, Any]:
    return {"hota": round(scores.hota, 4), "deta": round(scores.deta, 4), "assa": round(scores.assa, 4),
            "idf1": round(scores.idf1, 4), "mota": round(scores.mota, 4), "id_switches": scores.id_switches,
            "gt_boxes": scores.gt_boxes, "reported_boxes": scores.reported_boxes}


def _ms(times: dict[str, np.ndarray]) -> dict[str, dict[str, float]]:
    return {name: {"mean": round(float(np.mean(t)), 4), "p50": round(float(np.median(t)), 4),
                   "p95": round(float(np.percentile(t, 95)), 4)} for name, t in times.items() if len(t)}
