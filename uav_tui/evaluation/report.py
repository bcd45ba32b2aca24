"""Eval results out: a terminal table (rich), one JSON file, success and precision plots (PNG, Agg).

Failed jobs are listed (where and why) and left out of every score; ``eval.json`` is replaced atomically, so
a reader (or a run killed while writing it) never sees half a file.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from rich.markup import escape
from rich.table import Table

from uav_tui.evaluation.metrics import IOU_THRESHOLDS, PIXEL_THRESHOLDS, PRECISION_AT_PX, Scores, summarise
from uav_tui.evaluation.runner import JobResult
from uav_tui.output.text import safe

OVERALL = "overall"
"""The row / key of the scores over all sequences."""
CURVES = ("success_curve", "precision_curve", "norm_precision_curve")
PLOT_FILES = ("success.png", "precision.png")


def overall_scores(results: list[JobResult]) -> dict[str, Scores]:
    """Tracker label -> its scores over the sequences it did not fail on (in the order trackers first appear)."""
    by_tracker: dict[str, list[JobResult]] = {}
    for result in results:
        if result.scores is not None:
            by_tracker.setdefault(result.tracker, []).append(result)
    return {label: summarise([r.scores for r in runs if r.scores is not None],
                             np.concatenate([r.times_ms for r in runs]))
            for label, runs in by_tracker.items()}


def summary(results: list[JobResult], sources: Iterable[str] = (), *, total_jobs: int | None = None
            ) -> dict[str, Any]:
    """The JSON document: per tracker, its overall scores and each sequence's (with the curves), and its failures.

    ``total_jobs``: how many jobs the evaluation has (``jobs_done`` says how many of them are in).
    """
    overall = overall_scores(results)
    trackers: dict[str, Any] = {}
    for result in results:
        entry = trackers.setdefault(result.tracker, {"sequences": {}, "failed": {}})
        if result.scores is None:
            entry["failed"][result.sequence] = {"error": result.error, "at": result.failed_at,
                                                "traceback": result.traceback}
        else:
            entry["sequences"][result.sequence] = {**result.scores.as_dict(), "saves": result.saves,
                                                   "save_calls": result.save_calls}
    for label, scores in overall.items():
        trackers[label][OVERALL] = scores.as_dict()
    sequences = list(dict.fromkeys(r.sequence for r in results))
    return {"protocol": "one-pass (OPE): catch_cmd(frame 1 gt box), photo_processing on every frame",
            "sources": list(sources), "threads": results[0].threads if results else None,
            "jobs_done": len(results), "jobs_total": len(results) if total_jobs is None else total_jobs,
            "jobs_failed": sum(r.failed for r in results), "sequences": sequences, "trackers": trackers}


def headline(document: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Tracker label -> its overall scores without the curves (what a benchmark prints)."""
    return {label: {key: _rounded(value) for key, value in entry[OVERALL].items() if key not in CURVES}
            for label, entry in document["trackers"].items() if OVERALL in entry}


def write_json(document: dict[str, Any], path: Path) -> Path:
    """Write ``document`` to ``path`` atomically (a temporary file beside it, then renamed over it)."""
    text = json.dumps(document, indent=1, allow_nan=False, default=_plain)
    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(handle, "w") as file:
            file.write(text)
            file.flush()
            os.fsync(file.fileno())
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
    return path


def table(results: list[JobResult]) -> Table:
    """Per sequence and overall: success AUC, precision@20, normalised precision, frames lost while visible,
    share of absent frames reported lost, reappearances found again within 1 s, mean frames to report a
    disappearance lost, ms/frame, FPS, ``tmMgr.save`` images stored / calls; failed jobs say
    where and why (under the table: :func:`failures`)."""
    threads = {r.threads for r in results}
    grid = Table(title="one-pass evaluation", caption=f"OpenCV/ONNX threads per job: "
                 f"{', '.join(str(t) for t in sorted(threads))}", show_lines=False)
    grid.add_column("sequence", no_wrap=True,
                    min_width=max(len(OVERALL), *(len(safe(r.sequence)) for r in results)))
    grid.add_column("tracker", overflow="fold")
    for name in ("AUC", f"P@{PRECISION_AT_PX}", "NP", "lost visible", "absent lost", "re-acquired 1 s",
                 "frames to lost", "ms mean", "p50", "p95", "FPS",
                 "saved"):
        grid.add_column(name, justify="right", no_wrap=False)
    for result in results:
        if result.scores is None:
            grid.add_row(outside_cell(result.sequence), outside_cell(result.tracker), "[red]failed[/red]",
                         f"[red]{outside_cell(result.failed_at)}[/red]", *["-"] * 9, _saved(result))
        else:
            grid.add_row(outside_cell(result.sequence), outside_cell(result.tracker), *_cells(result.scores),
                         _saved(result))
    grid.add_section()
    for label, scores in overall_scores(results).items():
        runs = [r for r in results if r.tracker == label]
        saved = f"{sum(r.saves for r in runs)}/{sum(r.save_calls for r in runs)}"
        grid.add_row(f"[b]{OVERALL}[/b]", f"[b]{outside_cell(label)}[/b]", *_cells(scores), saved)
    return grid


def failures(results: list[JobResult]) -> list[str]:
    """One line per failed job: ``TRACKER on SEQUENCE failed at frame 5: ValueError: text (file.py:12)``, passed
    through :func:`safe` (names and messages come from outside)."""
    return [safe(f"{r.tracker} on {r.sequence} failed at {r.failed_at}: {r.error}") for r in results if r.failed]


def outside_cell(text: object) -> str:
    """Outside text (a name, a path) as Rich markup: :func:`safe` (no control character reaches the terminal),
    then Rich's escape (no ``[b]`` in a folder name is taken for markup)."""
    return escape(safe(str(text)))


def write_plots(results: list[JobResult], folder: Path) -> list[Path]:
    """``success.png`` and ``precision.png``: one curve per tracker over all sequences, score in the legend."""
    overall = overall_scores(results)
    paths: list[Path] = []
    if not overall:
        return paths
    for name, thresholds, curve, score, xlabel, title in (
        (PLOT_FILES[0], IOU_THRESHOLDS, "success_curve", "success_auc", "overlap threshold (IoU >)", "Success plot"),
        (PLOT_FILES[1], PIXEL_THRESHOLDS, "precision_curve", "precision_20", "location error threshold (px)",
         "Precision plot"),
    ):
        figure = Figure(figsize=(7, 4.5 + 0.2 * len(overall)), layout="constrained")
        axes = figure.add_subplot()
        ranked = sorted(overall.items(), key=lambda item: -getattr(item[1], score))
        for label, scores in ranked:
            axes.plot(thresholds, getattr(scores, curve), label=f"[{getattr(scores, score):.3f}] {label[:80]}")
        axes.set(xlabel=xlabel, ylabel="fraction of frames", ylim=(0, 1), xlim=(thresholds[0], thresholds[-1]),
                 title=f"{title} of OPE ({len({r.sequence for r in results if not r.failed})} sequences)")
        axes.grid(alpha=0.3)
        figure.legend(loc="outside lower center", fontsize="small")  # below the plot: labels can be long
        path = folder / name
        figure.savefig(path, dpi=100)
        paths.append(path)
    return paths


def _cells(scores: Scores) -> list[str]:
    absent = "-" if scores.absent_lost_share is None else f"{100 * scores.absent_lost_share:.0f}%"
    back = f"{scores.reacquired}/{scores.reappearances}" if scores.reappearances else "-"
    to_lost = "-" if scores.frames_to_lost is None else f"{scores.frames_to_lost:.1f}"
    return [f"{scores.success_auc:.3f}", f"{scores.precision_20:.3f}", f"{scores.norm_precision:.3f}",
            str(scores.frames_lost), absent, back, to_lost, f"{scores.ms_mean:.1f}", f"{scores.ms_p50:.1f}",
            f"{scores.ms_p95:.1f}", f"{scores.fps:.0f}"]


def _saved(result: JobResult) -> str:
    """Images stored / ``tmMgr.save`` calls (the rest over the cap or the rate)."""
    return f"{result.saves}/{result.save_calls}"


def _rounded(value: Any) -> Any:
    return round(value, 4) if isinstance(value, float) and math.isfinite(value) else value


def _plain(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON")
