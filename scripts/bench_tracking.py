"""``uav-tui eval`` on the whole aerial-tracking set: csrt fast, csrt paper and plain OpenCV trackers; prints JSON.

    .venv/bin/python scripts/bench_tracking.py [--data DIR] [--workers N] [--out DIR]

The summary has each tracker's overall scores (success AUC, precision@20px, normalised precision,
frames lost, ms/frame) and, for each csrt mode, its AUC and mean ms/frame relative to plain CSRT's
measured in the same run. The default data folder is ``aerial-tracking`` in the shared data folder
(``$UAV_TUI_DATA_DIR``, else ``shared/data`` beside the repository).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from processors.detection import find_data_dir  # noqa: E402
from uav_tui.evaluation import TrackerSpec, evaluate, find_sequences  # noqa: E402
from uav_tui.evaluation.report import headline, summary, write_json, write_plots  # noqa: E402

TRACKERS = [TrackerSpec("csrt", {"mode": "fast"}), TrackerSpec("csrt", {"mode": "paper"}), TrackerSpec("cv:csrt"),
            TrackerSpec("cv:kcf"), TrackerSpec("cv:mil")]
BASELINE = "cv:csrt"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=find_data_dir() / "aerial-tracking")
    parser.add_argument("--workers", type=int, default=1,
                        help="jobs at once (default 1: a tracker's ms/frame is not measured beside another's)")
    parser.add_argument("--out", type=Path, help="also write eval.json and the plots here")
    args = parser.parse_args()
    sequences = find_sequences([args.data])
    results = evaluate(sequences, TRACKERS, workers=args.workers)
    document = summary(results, [str(args.data)])
    out = args.out or Path(tempfile.mkdtemp(prefix="bench_tracking-"))
    out.mkdir(parents=True, exist_ok=True)
    write_json(document, out / "eval.json")
    write_plots(results, out)
    overall = headline(document)
    base = overall[BASELINE]
    ratios = {label: {"auc_minus_plain_csrt": round(scores["success_auc"] - base["success_auc"], 4),
                      "auc_ratio": round(scores["success_auc"] / base["success_auc"], 3),
                      "ms_ratio": round(scores["ms_mean"] / base["ms_mean"], 3),
                      "frames_lost_vs_plain": f"{scores['frames_lost']} vs {base['frames_lost']}"}
              for label, scores in overall.items() if label.startswith("csrt")}
    print(json.dumps({"data": str(args.data), "sequences": len(sequences),
                      "frames": base["frames"], "workers": args.workers, "trackers": overall,
                      "versus_plain_csrt": ratios, "written": str(out)}, indent=1))


if __name__ == "__main__":
    main()
