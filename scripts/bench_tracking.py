"""``uav-tui eval`` on the whole aerial-tracking set: the trackers of issue 37 and its goals, as JSON.

    .venv/bin/python scripts/bench_tracking.py [--data DIR] [--workers N] [--threads N] [--out DIR]

Trackers: ``nanotrack``, ``csrt`` (fast and paper), and plain OpenCV's ``cv:nano``, ``cv:csrt``, ``cv:kcf``.
Per tracker the summary has its overall success AUC, precision@20px, frames lost while the target is
visible, the share of absent-target frames (gt ``NaN``) it reported lost (as ``uav-tui eval``: the mean
over the sequences that have such frames), and ms/frame; then each goal, as a difference or ratio
measured within this one run, with ``pass`` true or false (null when a tracker it needs is missing or
failed). A tracker that cannot be loaded is left out and named under ``missing``; a job that raised is
named under ``failed`` (where and why) and left out of the scores. The default data folder is
``aerial-tracking`` in the shared data folder (``$UAV_TUI_DATA_DIR``, else ``shared/data`` beside the
repository).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from uav_tui.errors import ConfigError  # noqa: E402
from uav_tui.evaluation import TrackerSpec, evaluate, find_sequences  # noqa: E402
from uav_tui.evaluation.report import headline, summary, write_json  # noqa: E402
from uav_tui.evaluation.sequences import aerial_tracking_set  # noqa: E402

NANOTRACK, CSRT_FAST = "nanotrack", "csrt mode=fast"
PLAIN_NANO, PLAIN_CSRT = "cv:nano", "cv:csrt"
TRACKERS = [TrackerSpec("nanotrack"), TrackerSpec("csrt", {"mode": "fast"}), TrackerSpec("csrt", {"mode": "paper"}),
            TrackerSpec("cv:nano"), TrackerSpec("cv:csrt"), TrackerSpec("cv:kcf")]


def loadable(trackers: list[TrackerSpec]) -> tuple[list[TrackerSpec], dict[str, str]]:
    """The trackers that construct here, and label -> why for those that do not."""
    found, missing = [], {}
    for tracker in trackers:
        try:
            tracker.load()
        except Exception as exc:  # noqa: BLE001 - any reason a tracker cannot load is reported, not fatal
            missing[tracker.label] = f"{type(exc).__name__}: {exc}"
        else:
            found.append(tracker)
    return found, missing


Measure = Callable[[dict[str, dict[str, Any]]], float | None]

GOALS: list[tuple[str, str, tuple[str, ...], Measure, str, float]] = [
    (NANOTRACK, "success AUC minus cv:nano's", (NANOTRACK, PLAIN_NANO),
     lambda t: t[NANOTRACK]["success_auc"] - t[PLAIN_NANO]["success_auc"], ">=", 0.02),
    (NANOTRACK, "precision@20 minus cv:nano's", (NANOTRACK, PLAIN_NANO),
     lambda t: t[NANOTRACK]["precision_20"] - t[PLAIN_NANO]["precision_20"], ">=", 0.0),
    (NANOTRACK, "share of visible frames lost", (NANOTRACK,), lambda t: t[NANOTRACK]["lost_while_visible_share"],
     "<=", 0.03),
    (NANOTRACK, "share of absent frames reported lost", (NANOTRACK,),
     lambda t: t[NANOTRACK]["absent_reported_lost_share"], ">=", 0.5),
    (NANOTRACK, "ms/frame over cv:nano's", (NANOTRACK, PLAIN_NANO),
     lambda t: t[NANOTRACK]["ms_mean"] / t[PLAIN_NANO]["ms_mean"], "<=", 1.2),
    (CSRT_FAST, "success AUC minus cv:csrt's", (CSRT_FAST, PLAIN_CSRT),
     lambda t: t[CSRT_FAST]["success_auc"] - t[PLAIN_CSRT]["success_auc"], ">=", 0.0),
    (CSRT_FAST, "ms/frame over cv:csrt's", (CSRT_FAST, PLAIN_CSRT),
     lambda t: t[CSRT_FAST]["ms_mean"] / t[PLAIN_CSRT]["ms_mean"], "<=", 0.5),
]
"""Issue 37's goals: (tracker, what is measured, trackers it needs, how, comparison, bound)."""


def goals(trackers: dict[str, dict[str, Any]], unusable: set[str]) -> dict[str, dict[str, Any]]:
    """Each goal measured on this run's overall scores: value, bound and ``pass`` (None when it cannot be told)."""
    verdicts: dict[str, dict[str, Any]] = {}
    for owner, name, needs, measure, comparison, bound in GOALS:
        gone = [label for label in needs if label in unusable or label not in trackers]
        value = None if gone else measure(trackers)
        verdict: dict[str, Any] = {"goal": f"{comparison} {bound:g}"}
        if value is None:
            verdict.update(value=None, why=f"{', '.join(gone)} missing or failed" if gone else "nothing to measure",
                           **{"pass": None})
        else:
            verdict.update(value=round(value, 4), **{"pass": value >= bound if comparison == ">=" else value <= bound})
        verdicts.setdefault(owner, {})[name] = verdict
    return verdicts


def run(data: Path, trackers: list[TrackerSpec], workers: int, threads: int, out: Path) -> dict[str, Any]:
    """Evaluate ``trackers`` on every sequence under ``data``; the benchmark's JSON document."""
    sequences = find_sequences([data])
    usable, missing = loadable(trackers)
    results = evaluate(sequences, usable, workers=workers, threads=threads) if usable else []
    document = summary(results, [str(data)])
    out.mkdir(parents=True, exist_ok=True)
    write_json(document, out / "eval.json")
    overall = {label: _row(scores) for label, scores in headline(document).items()}
    failed: dict[str, dict[str, str]] = {}
    for result in results:
        if result.failed:
            failed.setdefault(result.tracker, {})[result.sequence] = f"{result.failed_at}: {result.error}"
    return {"data": str(data), "sequences": len(sequences), "workers": workers, "threads": threads,
            "trackers": overall, "missing": missing, "failed": failed,
            "goals": goals(overall, set(missing) | set(failed)), "written": str(out)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, help="the sequences (default: the aerial-tracking set where the "
                        "tests find it)")
    parser.add_argument("--workers", type=int, default=1,
                        help="jobs at once (default 1: a tracker's ms/frame is not measured beside another's)")
    parser.add_argument("--threads", type=int, default=1, help="OpenCV/ONNX threads of each job (default 1)")
    parser.add_argument("--out", type=Path, help="also keep eval.json here (default: a temporary folder)")
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="bench_tracking-"))
    try:
        data = args.data or aerial_tracking_set()
    except ConfigError as exc:
        parser.error(str(exc))
    print(json.dumps(run(data, TRACKERS, args.workers, args.threads, out), indent=1))


def _row(scores: dict[str, Any]) -> dict[str, Any]:
    """What the benchmark prints of a tracker's overall scores (eval's names, and the issue's)."""
    visible = scores["scored"]
    return {"success_auc": scores["success_auc"], "precision_20": scores["precision_20"],
            "visible_frames": visible, "lost_while_visible": scores["frames_lost"],
            "lost_while_visible_share": round(scores["frames_lost"] / visible, 4) if visible else None,
            "absent_frames": scores["absent_frames"], "absent_reported_lost": scores["absent_lost"],
            "absent_reported_lost_share": scores["absent_lost_share"], "ms_mean": scores["ms_mean"],
            "ms_p95": scores["ms_p95"]}


if __name__ == "__main__":
    main()
