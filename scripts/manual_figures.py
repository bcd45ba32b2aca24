"""Write the manual's measured figures from the benchmarks' JSON, so that no number in it is typed by hand.

    .venv/bin/python scripts/bench_tracking.py > scripts/results/tracking.json
    .venv/bin/python scripts/bench_precland.py > scripts/results/precland.json
    .venv/bin/python scripts/bench_geolocation.py > scripts/results/geolocation.json
    .venv/bin/uav-tui bench --out scripts/results/bench.json
    .venv/bin/python scripts/bench_video_out.py > scripts/results/video_out.json
    .venv/bin/python scripts/bench_video_out.py --rtsp > scripts/results/video_out_rtsp.json
    .venv/bin/python scripts/bench_detection.py > scripts/results/detection.json
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


GEO_VIEWS = (("down_level", "views, camera down, level"),
             ("down_rolling_pitching", "views, camera down, rolling and pitching ±15°"),
             ("oblique60_rolling_pitching", "views, camera 60° down, rolling and pitching ±15°"))
"""``bench_geolocation.py``'s rendered cases: (JSON key after the height, row label)."""
GEO_FLIGHT = (("hovering", "flight, hovering"), ("flying_2ms", "flight, at 2 m/s"),
              ("all", "flight, every frame (the climb too)"))
"""``bench_geolocation.py``'s parts of a recorded flight: (JSON key, row label)."""
GEO_COSTS = {"pinhole": "one projection", "distorted": "one projection, with lens distortion",
             "frame_row": "a frame row's projection (height chosen by name, readings' ages checked)",
             "32_detections_rows": "a frame's 32 detections into detections.csv rows (writer thread)",
             "velocity_position_added": "the target's velocity: a position added (each frame)",
             "velocity_fit": "the target's velocity: the fit (once a second)"}
"""``bench_geolocation.py``'s timed calls: JSON key -> row label (an unknown key is shown as it is)."""


def geolocation(result: dict[str, Any]) -> str:
    """``bench_geolocation.py``: the error against the simulator's truth by height (rendered views, recorded flights),
    what an attitude or height error adds, the cost of a projection, the goals."""
    def error_row(height: str, label: str, count: int, part: dict[str, Any]) -> str:
        error, stated = part["error"], part["stated_uncertainty_1sigma"]
        return (f"| {height} | {label} | {count} | {error['p50_m']} m | {error['p95_m']} m | {error['max_m']} m | "
                f"{part['within_stated_uncertainty']:.1%} | {stated['p50_m']} m |")

    errors = ["| height | where | frames | p50 | p95 | max | within the stated 1σ | stated 1σ, p50 |",
              "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    added = ["| height | views | 1° of roll and pitch off, p50 / p95 | 0.5 m of height off, p50 / p95 |",
             "| --- | --- | --- | --- |"]
    sources = []
    heights = sorted({name.split("_", 1)[0] for name in result["hover_perfect_attitude"]}, key=lambda h: float(h[:-1]))
    for height in heights:
        shown = height.replace("m", " m")
        for key, label in GEO_VIEWS:
            view = result["hover_perfect_attitude"][f"{height}_{key}"]
            errors.append(error_row(shown, label, view["views"], view))
            attitude, off = view["error_with_roll_and_pitch_off_1deg"], view["error_with_height_off_0.5m"]
            added.append(f"| {shown} | {label.removeprefix('views, ')} | {attitude['p50_m']} / {attitude['p95_m']} m | "
                         f"{off['p50_m']} / {off['p95_m']} m |")
        flown = result.get("flight_recorded", {}).get(height)
        if flown is not None:
            errors += [error_row(shown, label, flown[key]["frames"], flown[key]) for key, label in GEO_FLIGHT]
            sources.append(f"{shown}: " + ", ".join(f"{name} {count}" for name, count in flown["height_from"].items()))
    costs = ["| call | p50 | p95 |", "| --- | --- | --- |"]
    costs += [f"| {GEO_COSTS.get(name, name)} | {cost['p50_ms']} ms | {cost['p95_ms']} ms |"
              for name, cost in result["cost_per_projection"].items()]
    sigma = result["assumed_1sigma"]
    notes = [f"Stated uncertainty from the assumed 1σ errors: roll and pitch {sigma['roll_pitch_deg']:g}°, yaw "
             f"{sigma['yaw_deg']:g}°, height {sigma['rangefinder_height_m']:g} m from a rangefinder, "
             f"{sigma['terrain_height_m']:g} m above the terrain, {sigma['height_above_home_m']:g} m above home."
             + (f" The flights' height came from (frames): {'; '.join(sources)}." if sources else ""),
             f"Load average {result['load_average_1min_at_end']:g} on {result['cpus']} cores at the end.", "",
             *(f"- {line}" for line in _verdicts(result))]
    return "\n".join([*errors, "", *added, "", *costs, "", *notes]) + "\n"


PAPER_TABLE_1 = {"template": "30", "csrt": "18 (CSRT + SIFT)", "position_hold": "2 (SIFT hold)", "yolo": "3"}
"""The seed paper's Table 1: FPS of its processors on a Raspberry Pi 4B at 640x480."""


def bench(result: dict[str, Any]) -> str:
    """``uav-tui bench``: each processor's FPS and CPU a frame at each resolution, beside the paper's Table 1."""
    resolutions = list(dict.fromkeys(row["resolution"] for row in result["rows"]))
    rows = ["| processor | paper, Pi 4B 640x480 FPS | " + " | ".join(f"{r} FPS | {r} CPU ms a frame"
                                                                     for r in resolutions) + " |",
            "| --- | --- | " + " | ".join("--- | ---" for _ in resolutions) + " |"]
    for processor in dict.fromkeys(row["processor"] for row in result["rows"]):
        cells = [f"`{processor}`", PAPER_TABLE_1.get(processor, "-")]
        for resolution in resolutions:
            row = next(r for r in result["rows"] if (r["processor"], r["resolution"]) == (processor, resolution))
            cells += ["-", "-"] if "error" in row else [f"{row['fps']:g}", f"{row['cpu_ms_per_frame']:g}"]
        rows.append("| " + " | ".join(cells) + " |")
    machine = result["machine"]
    notes = [f"{machine['cpus']} cores ({machine['machine']}{', ' + machine['model'] if machine['model'] else ''}), "
             f"{result['seconds']:g} s measured each, {result['video']}; load average "
             f"{machine['load_average_1min_at_end']:g} at the end."]
    return "\n".join([*rows, "", *notes]) + "\n"


def video_out(result: dict[str, Any]) -> str:
    """``bench_video_out.py`` (RTP/UDP, or ``--rtsp``): latency to a decoding receiver, the CPU the stream adds, FPS
    on / off."""
    on, off, latency = result["on"], result["off"], result["on"]["latency_ms"]
    rows = ["| measure | value |", "| --- | --- |",
            f"| capture to decoded at the receiver, p50 / p95 / max | {latency['p50']} / {latency['p95']} / "
            f"{latency['max']} ms |",
            f"| CPU of the platform (and processor), stream off / on | {off['core_share']:.1%} / "
            f"{on['core_share']:.1%} of a core |",
            f"| processed FPS, stream off / on | {off['processed_fps']} / {on['processed_fps']} |",
            f"| frames sent / slots missed / errors | {on['video']['sent']} / {on['video']['dropped']} / "
            f"{on['video']['errors']} |"]
    if result["benchmark"] == "video_out_rtsp":
        rows.append(f"| frames to no client (before the receiver played, or its queue full) | "
                    f"{on['video']['unsent']} |")
    notes = [f"{result.get('transport', 'RTP/UDP')}: {result['size']} at {result['fps']} FPS, {result['kbps']} "
             f"kbit/s, `{on['video']['encoder']}`, {on['decoded_frames']} frames decoded by FFmpeg on loopback; "
             f"load average {result['load_average_1min_at_end']:g} on {result['cpus']} cores at the end.", "",
             *(f"- {line}" for line in _verdicts(result))]
    return "\n".join([*rows, "", *notes]) + "\n"


RUNTIME_NAMES = {"opencv": "OpenCV DNN", "onnxruntime": "ONNX Runtime"}
"""``bench_detection.py``'s runtimes as the manual names them."""


def detection(result: dict[str, Any]) -> str:
    """``bench_detection.py``: FPS and CPU a frame of the shipped ``yolo`` on each runtime, detecting on every frame
    or every 3rd, the platform's tracker beside it; how long opening the detector takes."""
    rows = ["| runtime | detector runs on | FPS | CPU ms a frame | tracker CPU ms a frame | tracker / processor |",
            "| --- | --- | --- | --- | --- | --- |"]
    for name, run in result["runs"].items():
        runtime, _, every = name.partition("_every_")
        on = "every frame" if every == "1" else f"1 frame in {every}, optical flow between"
        rows.append(f"| {RUNTIME_NAMES[runtime]} | {on} | {run['fps']:g} | {run['cpu_s_per_frame'] * 1000:.2f} | "
                    f"{run['tracker_cpu_s_per_frame'] * 1000:.3f} | {run['tracker_share_of_detector']:.1%} |")
    ratio, load, machine = result["opencv_cpu_over_onnxruntime_cpu"], result["load_s"], result["machine"]
    sequences = ", ".join(f"`{name}`" for name in result["sequences"])
    notes = [f"{result['frames']} frames of {sequences} at {result['size']}, the round of {result['rounds']} with the "
             f"least CPU. OpenCV DNN's CPU a frame over ONNX Runtime's: {ratio['every_1']:g}x detecting on every "
             f"frame, {ratio['every_3']:g}x on every 3rd. Opening the detector: OpenCV DNN {load['opencv']:g} s, ONNX "
             f"Runtime {load['onnxruntime_first']:g} s the first time (converting the model), "
             f"{load['onnxruntime_cached']:g} s after. ONNX Runtime {machine['onnxruntime']}, OpenCV "
             f"{machine['opencv']} ({machine['opencv_threads']} threads); load average "
             f"{machine['load_average_1min_at_end']:g} on {machine['cores']} cores at the end.", "",
             f"- the tracker under {result['goal_tracker_share']:.0%} of the processor's CPU a frame: "
             f"{'met' if result['goal_tracker_share_met'] else 'not met'}"]
    return "\n".join([*rows, "", *notes]) + "\n"


RENDERERS: dict[str, Callable[[dict[str, Any]], str]] = {"tracking": tracking, "precland": precland,
                                                         "geolocation": geolocation, "bench": bench,
                                                         "video_out": video_out, "video_out_rtsp": video_out,
                                                         "detection": detection}
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
