"""``uav-tui bench``: what each reference processor does on this computer, as the seed paper's Table 1 says it.

Each processor runs through the whole platform (its own process, as it flies) on a clip at each resolution, as
fast as the computer goes, and the table gives processed frames a second and CPU milliseconds a frame (the
platform's and the processor's process together; 1000 ms a frame is one core). The clip is a generated scene,
or the user's own (``--video``, a recording's ``video.ts`` or any video file), resized to each resolution.
Trackers (csrt, nanotrack) are given the middle of the frame to follow. A processor that cannot run here
(a missing extra) is a row that says why. The table goes to the terminal and, whole, to a JSON file.
"""

from __future__ import annotations

import argparse
import asyncio
import datetime
import json
import os
import platform
import tempfile
from collections.abc import Iterator
from itertools import islice
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from sources.synthetic import SyntheticScene
from uav_tui.arguments import ArgumentParser
from uav_tui.errors import KNOWN_ERRORS, error_line
from uav_tui.evaluation.throughput import platform_run
from uav_tui.output.text import safe

PROCESSORS = ("template", "csrt", "position_hold", "nanotrack", "yolo", "precision_land")
"""The reference processors, in the paper's order first (template matching, CSRT, SIFT hold, YOLO)."""
TRACKERS = frozenset({"csrt", "nanotrack"})
"""Processors that follow a selection: given the middle of the frame."""
RESOLUTIONS = ("640x480", "1280x720")
CLIP_FRAMES = 150
CLIP_FPS = 30


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(prog="uav-tui bench", description=__doc__.splitlines()[0])
    parser.add_argument("--processors", default=",".join(PROCESSORS), help="comma-separated (default: all)")
    parser.add_argument("--resolutions", default=",".join(RESOLUTIONS), help="comma-separated WxH")
    parser.add_argument("--video", type=Path, help="your clip (default: a generated scene)")
    parser.add_argument("--seconds", type=float, default=5.0, help="measured per processor and resolution")
    parser.add_argument("--warm-up", type=float, default=3.0, help="seconds run before measuring")
    parser.add_argument("--out", type=Path, help="the JSON file (default: bench-<UTC time>.json here)")
    return parser


def main(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    try:
        sizes = [_size(text) for text in args.resolutions.split(",")]
        if not (args.seconds > 0 and args.warm_up >= 0):
            raise ValueError("--seconds must be > 0 and --warm-up >= 0")
        if args.video is not None and not args.video.is_file():
            raise ValueError(f"--video {args.video}: no such file")
    except ValueError as exc:
        build_parser().error(str(exc))
    out = args.out or Path(f"bench-{datetime.datetime.now(datetime.UTC):%Y%m%dT%H%M%SZ}.json")
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="uav-tui-bench-") as folder:
        for size in sizes:
            clip = _write_clip(Path(folder) / f"{size[0]}x{size[1]}.mp4", size, args.video)
            for processor in args.processors.split(","):
                rows.append(_measure(processor.strip(), size, clip, args.seconds, args.warm_up))
                print(_line(rows[-1]), flush=True)
    machine = {**_machine(), "load_average_1min_at_end": round(os.getloadavg()[0], 2)}
    document = {"machine": machine, "video": str(args.video or "generated scene"), "seconds": args.seconds,
                "rows": rows}
    out.write_text(json.dumps(document, indent=1) + "\n")
    print(f"\n{table(rows)}\nsaved {safe(str(out))}")
    return 0 if all("error" not in row for row in rows) else 1


def _size(text: str) -> tuple[int, int]:
    width, _, height = text.strip().partition("x")
    try:
        size = int(width), int(height)
    except ValueError:
        raise ValueError(f"resolution {text!r}: expected WxH, e.g. 640x480") from None
    if not (16 <= size[0] <= 7680 and 16 <= size[1] <= 4320):
        raise ValueError(f"resolution {text!r}: expected 16x16 to 7680x4320")
    return size


def _frames(size: tuple[int, int], video: Path | None) -> Iterator[np.ndarray]:
    if video is None:
        scene = SyntheticScene(*size, seed=1)
        yield from (scene.render(i) for i in range(CLIP_FRAMES))
        return
    capture = cv2.VideoCapture(str(video))
    try:
        while (frame := capture.read()[1]) is not None:
            yield cv2.resize(frame, size, interpolation=cv2.INTER_AREA)
    finally:
        capture.release()


def _write_clip(path: Path, size: tuple[int, int], video: Path | None) -> Path:
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"mp4v"), CLIP_FPS, size)
    written = 0
    for frame in islice(_frames(size, video), CLIP_FRAMES):
        writer.write(frame)
        written += 1
    writer.release()
    if written == 0:
        raise SystemExit(f"uav-tui bench: no frame could be read from {safe(str(video))}")
    return path


def _measure(processor: str, size: tuple[int, int], clip: Path, seconds: float, warm_up: float) -> dict[str, Any]:
    row: dict[str, Any] = {"processor": processor, "resolution": f"{size[0]}x{size[1]}"}
    width, height = size
    roi = (width * 7 // 16, height * 7 // 16, width // 8, height // 8) if processor in TRACKERS else None
    try:
        measures, _ = asyncio.run(platform_run(f"file:{clip}?realtime=0", processor, "process", seconds, roi,
                                               warm_up_s=warm_up))
    except KNOWN_ERRORS as exc:
        return {**row, "error": error_line(exc)}
    return {**row, "fps": round(measures["fps"], 1), "cpu_ms_per_frame": round(measures["cpu_s_per_frame"] * 1e3, 2),
            "frames": measures["frames"], "latency_ms_p50": round(measures["latency_ms_p50"], 1)}


def _line(row: dict[str, Any]) -> str:
    where = f"{row['processor']} {row['resolution']}"
    if "error" in row:
        return safe(f"{where}: {row['error']}")
    return safe(f"{where}: {row['fps']:g} FPS, {row['cpu_ms_per_frame']:g} ms CPU a frame")


def table(rows: list[dict[str, Any]]) -> str:
    """The rows as a text table, a processor a line, FPS and CPU ms a frame at each resolution."""
    resolutions = list(dict.fromkeys(row["resolution"] for row in rows))
    head = ["processor"] + [f"{r} {what}" for r in resolutions for what in ("FPS", "CPU ms")]
    lines = []
    for processor in dict.fromkeys(row["processor"] for row in rows):
        cells = [processor]
        for resolution in resolutions:
            row = next((r for r in rows if (r["processor"], r["resolution"]) == (processor, resolution)), None)
            if row is None or "error" in row:
                cells += ["-", "-"]
            else:
                cells += [f"{row['fps']:g}", f"{row['cpu_ms_per_frame']:g}"]
        lines.append(cells)
    widths = [max(len(line[i]) for line in [head, *lines]) for i in range(len(head))]
    text = ["  ".join(cell.ljust(w) if i == 0 else cell.rjust(w) for i, (cell, w) in enumerate(zip(line, widths,
                                                                                                  strict=True)))
            for line in [head, *lines]]
    errors = [f"{row['processor']} {row['resolution']}: {row['error']}" for row in rows if "error" in row]
    return "\n".join(safe(line) for line in text + errors)


def _machine() -> dict[str, Any]:
    model = Path("/proc/device-tree/model")
    return {"cpus": os.cpu_count(), "machine": platform.machine(), "python": platform.python_version(),
            "model": model.read_text(errors="replace").strip("\0\n") if model.is_file() else platform.processor()}
