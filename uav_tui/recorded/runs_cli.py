"""``uav-tui runs`` (list the recorded runs), ``uav-tui report [RUN]`` (draw a run's plots) and ``uav-tui export
[RUN]`` (its track and target positions as GeoJSON / KML)."""

from __future__ import annotations

import datetime
import json
import sys
from pathlib import Path
from typing import Any

from uav_tui.arguments import ArgumentParser
from uav_tui.config import find_config_file, load_config
from uav_tui.errors import KNOWN_ERRORS, UavError, error_line
from uav_tui.output.text import escape, redact, safe
from uav_tui.recording.crash import crash_summary


def main(name: str, argv: list[str]) -> int:
    """Run the tool ``name`` (``runs``, ``report`` or ``export``) with its arguments; returns the exit code."""
    parser = ArgumentParser(prog=f"uav-tui {name}")
    parser.add_argument("--runs-dir", metavar="DIR", help="folder holding the runs (default: runs_dir of the "
                        "configuration, 'runs')")
    parser.add_argument("--config", metavar="PATH", help="TOML file to take runs_dir from")
    if name in ("report", "export"):
        parser.description = ("Write PNG plots and summary.txt into a run's folder." if name == "report" else
                              "Write the vehicle's track and the geo-located targets into a run's folder: "
                              "track.geojson (QGIS) and/or track.kml (Google Earth).")
        parser.add_argument("run", nargs="?", metavar="RUN", help="run folder, or its name under the runs "
                            "folder (default: the newest run)")
    if name == "export":
        parser.add_argument("--geojson", action="store_true", help="write track.geojson (default: both)")
        parser.add_argument("--kml", action="store_true", help="write track.kml (default: both)")
    elif name != "report":
        parser.description = "List recorded runs: start, duration, frames, size."
    args = parser.parse_args(argv)
    try:
        runs_dir = Path(args.runs_dir or load_config(find_config_file(args.config)).recording.runs_dir).expanduser()
        if name == "report":
            return _report(find_run(runs_dir, args.run))
        if name == "export":
            formats = [f for f in ("geojson", "kml") if getattr(args, f)] or ["geojson", "kml"]
            return _export(find_run(runs_dir, args.run), formats)
        return _list(runs_dir)
    except KNOWN_ERRORS as exc:
        print(safe(error_line(exc, f"uav-tui {name}"), multiline=True), file=sys.stderr)
        return 2


def list_runs(runs_dir: Path) -> list[dict[str, Any]]:
    """One dict per run folder under ``runs_dir``, oldest first: name, path, start, duration_s, frames, bytes,
    processor (as it was named), source (URI without password)."""
    found = []
    for path in sorted(p for p in runs_dir.glob("*") if (p / "run.json").is_file()):
        try:
            info = json.loads((path / "run.json").read_text())
        except (OSError, ValueError):
            continue
        files = [p for p in path.rglob("*") if p.is_file()]
        start, end = info.get("start_wall_ns"), info.get("end_wall_ns")
        if end is None:  # killed: the newest file tells how long it ran
            end = max((int(p.stat().st_mtime_ns) for p in files), default=start)
        frames = info.get("recording", {}).get("frames")
        if frames is None:
            frames = max(0, _count_lines(path / "frames.csv") - 1)
        found.append({"name": path.name, "path": path, "start": info.get("start_utc", "?"),
                      "duration_s": (end - start) / 1e9 if start and end else None, "frames": frames,
                      "bytes": sum(p.stat().st_size for p in files), "finished": "end_wall_ns" in info,
                      "processor": _spec(info.get("processor")), "source": redact(_spec(info.get("source"), "uri"))})
    return found


def _list(runs_dir: Path) -> int:
    runs = list_runs(runs_dir)
    if not runs:
        print(safe(f"no recorded runs in {runs_dir}"))
        return 0
    print(f"{'run':<24} {'start (UTC)':<20} {'duration':>9} {'frames':>7} {'size':>9}  {'processor':<24} source")
    for run in runs:
        duration = "?" if run["duration_s"] is None else str(datetime.timedelta(seconds=round(run["duration_s"])))
        start = run["start"].replace("+00:00", "").replace("T", " ")
        note = "  (crashed)" if crash_summary(run["path"]) else "" if run["finished"] else "  (not closed)"
        print(f"{_cell(run['name'], 24):<24} {_cell(start, 20):<20} {duration:>9} {run['frames']:>7} "
              f"{run['bytes'] / 1e6:>7.1f}MB  {_cell(run['processor'], 24):<24} {_cell(run['source'], 40)}{note}")
    return 0


def find_run(runs_dir: Path, name: str | None) -> Path:
    """The run folder ``name`` names (a path, or a name under ``runs_dir``); the newest run for None."""
    if name is None:
        runs = list_runs(runs_dir)
        if not runs:
            raise UavError(f"no recorded runs in {runs_dir}")
        return runs[-1]["path"]
    for candidate in (Path(name).expanduser(), runs_dir / name):
        if (candidate / "run.json").is_file():
            return candidate
    raise UavError(f"{name} is neither a run folder nor a run in {runs_dir}; `uav-tui runs` lists them")


WRITE_FAILED = 5
"""Exit status of ``report`` and ``export`` when their files cannot be written (a full disk), as a run's."""


def _report(run_dir: Path) -> int:
    from uav_tui.recorded.report import write_report  # matplotlib is only imported when a report is drawn

    try:
        paths, text = write_report(run_dir)
    except OSError as exc:
        return _not_written(exc, "the report")
    print(text)  # safe already
    for path in paths:
        print(safe(f"wrote {path}"))
    return 0


def _export(run_dir: Path, formats: list[str]) -> int:
    from uav_tui.recorded import dataset, export

    run = dataset.load(run_dir)
    try:
        written = export.write(run, formats)
    except OSError as exc:
        return _not_written(exc, "the export")
    for path in written:
        print(safe(f"wrote {path}"))
    for problem in run.problems:
        print(safe(f"damaged run: {problem}"))
    if unnamed := export.without_frame_id(run):
        print(f"{unnamed} geo-located rows without a frame_id were left out")
    targets = int((run.frames["target_status"] == "ok").sum())
    print(f"{targets} target positions" if targets else "no target positions: the run has no frame whose box was "
          "geo-located (it needs a box, a camera model and GPS; see target_status in frames.csv)")
    return 0


def _not_written(exc: OSError, what: str) -> int:
    """Say once that ``what`` could not be written, and why; the files written whole before it stay."""
    print(safe(f"{what} could not be written: {exc.filename or 'a file'}: {exc.strerror or exc}; nothing half-written "
               "was left: free some space (or copy the run elsewhere) and run it again"), file=sys.stderr)
    return WRITE_FAILED


def _spec(part: Any, key: str = "spec") -> str:
    """What the user named (``template``, ``mine.py:Mine``, ``usb:0``) from a ``run.json`` section."""
    if not isinstance(part, dict):
        return "?"
    return str(part.get(key) or part.get("name") or "?")


def _cell(text: str, width: int) -> str:
    """``text`` safe for a terminal (control characters escaped) and at most ``width`` characters."""
    text = escape(text)
    return text if len(text) <= width else text[: width - 1] + "…"


def _count_lines(path: Path) -> int:
    try:
        with open(path, "rb") as handle:
            return sum(chunk.count(b"\n") for chunk in iter(lambda: handle.read(1 << 20), b""))
    except OSError:
        return 0
