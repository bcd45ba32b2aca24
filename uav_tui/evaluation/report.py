"""Eval results out: a terminal table (rich), one JSON file, success and precision plots (PNG, Agg)."""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from rich.markup import escape
from rich.table import Table

from uav_tui.evaluation.metrics import IOU_THRESHOLDS, PIXEL_THRESHOLDS, PRECISION_AT_PX, Scores, summarise
from uav_tui.evaluation.runner import JobResult

OVERALL = "overall"
"""The row / key of the scores over all sequences."""
CURVES = ("success_curve", "precision_curve", "norm_precision_curve")
PLOT_FILES = ("success.png", "precision.png")


def overall_scores(results: list[JobResult]) -> dict[str, Scores]:
    """Tracker label -> its scores over all sequences (in the order trackers first appear)."""
    by_tracker: dict[str, list[JobResult]] = {}
    for result in results:
        by_tracker.setdefault(result.tracker, []).append(result)
    return {label: summarise([r.scores for r in runs], np.concatenate([r.times_ms for r in runs]))
            for label, runs in by_tracker.items()}


def summary(results: list[JobResult], sources: Iterable[str] = ()) -> dict[str, Any]:
    """The JSON document: per tracker, its overall scores and each sequence's (with the curves)."""
    overall = overall_scores(results)
    trackers: dict[str, Any] = {label: {OVERALL: scores.as_dict(), "sequences": {}}
                                for label, scores in overall.items()}
    for result in results:
        trackers[result.tracker]["sequences"][result.sequence] = result.scores.as_dict()
    sequences = list(dict.fromkeys(r.sequence for r in results))
    return {"protocol": "one-pass (OPE): catch_cmd(frame 0 gt box), photo_processing on every frame",
            "sources": list(sources), "sequences": sequences, "trackers": trackers}


def headline(document: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Tracker label -> its overall scores without the curves (what a benchmark prints)."""
    return {label: {key: _rounded(value) for key, value in entry[OVERALL].items() if key not in CURVES}
            for label, entry in document["trackers"].items()}


def write_json(document: dict[str, Any], path: Path) -> Path:
    path.write_text(json.dumps(document, indent=1, allow_nan=False, default=_plain))
    return path


def table(results: list[JobResult]) -> Table:
    """Per sequence and overall: success AUC, precision@20, normalised precision, lost, ms/frame, FPS."""
    grid = Table(title="one-pass evaluation", show_lines=False)
    grid.add_column("sequence", no_wrap=True, min_width=max(len(OVERALL), *(len(r.sequence) for r in results)))
    grid.add_column("tracker", overflow="fold")
    for name in ("AUC", f"P@{PRECISION_AT_PX}", "NP", "lost", "ms mean", "p50", "p95", "FPS"):
        grid.add_column(name, justify="right", no_wrap=True)
    for result in results:
        grid.add_row(escape(result.sequence), escape(result.tracker), *_cells(result.scores))
    grid.add_section()
    for label, scores in overall_scores(results).items():
        grid.add_row(f"[b]{OVERALL}[/b]", f"[b]{escape(label)}[/b]", *_cells(scores))
    return grid


def write_plots(results: list[JobResult], folder: Path) -> list[Path]:
    """``success.png`` and ``precision.png``: one curve per tracker over all sequences, score in the legend."""
    overall = overall_scores(results)
    paths = []
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
                 title=f"{title} of OPE ({len({r.sequence for r in results})} sequences)")
        axes.grid(alpha=0.3)
        figure.legend(loc="outside lower center", fontsize="small")  # below the plot: labels can be long
        path = folder / name
        figure.savefig(path, dpi=100)
        paths.append(path)
    return paths


def _cells(scores: Scores) -> list[str]:
    return [f"{scores.success_auc:.3f}", f"{scores.precision_20:.3f}", f"{scores.norm_precision:.3f}",
            str(scores.frames_lost), f"{scores.ms_mean:.1f}", f"{scores.ms_p50:.1f}", f"{scores.ms_p95:.1f}",
            f"{scores.fps:.0f}"]


def _rounded(value: Any) -> Any:
    return round(value, 4) if isinstance(value, float) and math.isfinite(value) else value


def _plain(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON")
