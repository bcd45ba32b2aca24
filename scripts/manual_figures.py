"""Write the manual's measured figures from the benchmarks' JSON, so that no number in it is typed by hand.

    .venv/bin/python scripts/bench_tracking.py > scripts/results/tracking.json
    .venv/bin/python scripts/bench_precland.py > scripts/results/precland.json
    .venv/bin/python scripts/manual_figures.py           # rewrites the marked blocks of docs/benchmarks.md
    .venv/bin/python scripts/manual_figures.py --check   # exit 1 when docs/benchmarks.md differs from the JSON

Each block ``<!-- bench:NAME -->`` ... ``<!-- /bench:NAME -->`` in docs/benchmarks.md is made from
``scripts/results/NAME.json`` by the renderer of that name in :data:`RENDERERS`; the JSON is the
benchmark's own output, committed beside this script.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "benchmarks.md"
"""The manual's page that holds the marked blocks."""
RESULTS = ROOT / "scripts" / "results"
BLOCK = re.compile(r"(<!-- bench:(?P<name>[\w-]+) -->\n)(?P<body>.*?)(<!-- /bench:(?P=name) -->)", re.DOTALL)


def tracking(result: dict[str, Any]) -> str:
    """``bench_tracking.py``: one row per tracker, then its goals."""
    rows = ["| tracker | success AUC | precision@20 px | visible frames lost | ms/frame |",
            "| --- | --- | --- | --- | --- |"]
    for label, scores in result["trackers"].items():
        lost = scores.get("lost_while_visible")
        share = scores.get("lost_while_visible_share")
        rows.append(f"| `{label}` | {scores['success_auc']:.3f} | {scores['precision_20']:.3f} | "
                    f"{'-' if lost is None else lost}{'' if share is None else f' ({share:.1%})'} | "
                    f"{scores['ms_mean']:.1f} |")
    goals = [f"{owner}: {name} {verdict['value']} ({verdict['goal']}: "
             f"{ {True: 'met', False: 'not met', None: verdict.get('why', 'unknown')}[verdict['pass']] })"
             for owner, named in result.get("goals", {}).items() for name, verdict in named.items()]
    missing = [f"{label} not measured: {why}" for label, why in result.get("missing", {}).items()]
    notes = [f"{result['sequences']} sequences of `{Path(result['data']).name}`, {result['workers']} job(s) at a time, "
             f"{result['threads']} OpenCV/ONNX thread(s) each.", "", *(f"- {line}" for line in goals + missing)]
    return "\n".join([*rows, "", *notes]) + "\n"


def _verdicts(result: dict[str, Any]) -> list[str]:
    """Each goal of a benchmark's ``goals`` ({name: {goal, value, pass}}) as one line."""
    return [f"{name}: {verdict['value']} ({verdict['goal']}: {'met' if verdict['pass'] else 'not met'})"
            for name, verdict in result["goals"].items()]


PRECLAND_ROWS = (("landing error", "landing_error", "m"), ("`precland` to touchdown", "precland_to_touchdown", "s"),
                 ("capture to LANDING_TARGET at the autopilot", "capture_to_landing_target", "ms"),
                 ("of which the `sim:` camera's rendering", "sim_camera_render", "ms"),
                 ("of which the processor's own time", "processor_own_time", "ms"),
                 ("of which the platform's share", "platform_share", "ms"),
                 ("`time_usec` off the true capture", "time_usec_stamp_off_capture", "ms"))
"""``bench_precland.py``'s figures: (row label, JSON key, unit)."""


def precland(result: dict[str, Any]) -> str:
    """``bench_precland.py``: p50 / p95 / max of each figure, the platform's share in its parts, the goals."""
    rows = ["| measure | p50 | p95 | max |", "| --- | --- | --- | --- |"]
    figures = [(label, result[key], unit) for label, key, unit in PRECLAND_ROWS]
    figures += [(f"platform: {name.replace('_', ' ')}", value, "ms")
                for name, value in result["platform_share_parts"].items()]
    for label, value, unit in figures:
        rows.append(f"| {label} | {value[f'p50_{unit}']} {unit} | {value[f'p95_{unit}']} {unit} | "
                    f"{value[f'max_{unit}']} {unit} |")
    notes = [f"{result['landings']} landings ({result['simulator']}) from {result['altitude_m']:g} m, the marker up to "
             f"{result['max_offset_m']:g} m off, wind {result['wind_ne_ms'][0]:g},{result['wind_ne_ms'][1]:g} m/s "
             f"N,E ({result['wind_speed_ms']:g} m/s); {result['landing_targets_received']} LANDING_TARGETs; load "
             f"average {result['load_average_1min_at_end']:g} on {result['cpus']} cores at the end.", "",
             *(f"- {line}" for line in _verdicts(result))]
    return "\n".join([*rows, "", *notes]) + "\n"


RENDERERS: dict[str, Callable[[dict[str, Any]], str]] = {"tracking": tracking, "precland": precland}
"""Block name -> how its JSON (``scripts/results/NAME.json``) is written into the page."""


def render(text: str, results: Path = RESULTS) -> str:
    """``text`` with every marked block rewritten from its JSON."""
    def block(match: re.Match[str]) -> str:
        name = match["name"]
        if name not in RENDERERS:
            raise SystemExit(f"{PAGE.name}: no renderer for the block bench:{name}; known: {', '.join(RENDERERS)}")
        data = json.loads((results / f"{name}.json").read_text())
        return f"{match.group(1)}{RENDERERS[name](data)}{match.group(4)}"
    return BLOCK.sub(block, text)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help=f"only say whether {PAGE.relative_to(ROOT)} is up to date (exit 1 if not)")
    args = parser.parse_args()
    text = PAGE.read_text()
    new = render(text)
    if args.check:
        if new != text:
            print(f"{PAGE.relative_to(ROOT)} differs from scripts/results/*.json: run scripts/manual_figures.py",
                  file=sys.stderr)
            return 1
        return 0
    PAGE.write_text(new)
    return 0


if __name__ == "__main__":
    sys.exit(main())
