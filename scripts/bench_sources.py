"""Capture cost and frame age per camera source at 640x480, 30 FPS. Prints JSON.

For each source the benchmark opens it, reads every new frame the way the processor worker does
(``wait_newer``) for a few seconds, and reports:

- ``delivered_fps``: frames the reader got per second;
- ``cpu_percent_of_one_core``: this process's CPU time over wall time (the capture thread, FFmpeg's
  decoder threads and the cheap reader), so 100 means one full core;
- ``cpu_ms_per_frame``: the same CPU time divided by the frames captured;
- ``frame_age_ms``: capture-to-reader delay (median, p95): how old a frame is when the processor
  could start on it;
- ``open_s``: time to open.

Sources: synthetic, file (a generated clip), usb (the UsbSource class reading a generated clip
through a capture that blocks like a camera driver, since there is no camera here), sim (with a
moving pose), rtsp (an H.264 server on loopback in a separate process, so its encoding is not
counted) and http MJPEG (likewise).

Usage: python scripts/bench_sources.py [--seconds 4] [--only sim,file]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sources import create_source  # noqa: E402
from sources.base import CameraSource  # noqa: E402
from sources.pose import PoseAt  # noqa: E402
from sources.sim_geometry import Pose  # noqa: E402
from sources.uri import SourceUri  # noqa: E402
from sources.usb import UsbSource  # noqa: E402

WIDTH, HEIGHT, FPS = 640, 480, 30

SERVER_SCRIPT = """
import sys, time
from tests.sources.stream_servers import MjpegTestServer, RtspTestServer
server = {"rtsp": RtspTestServer, "http": MjpegTestServer}[sys.argv[1]](640, 480, 30)
server.start()
print(server.url, flush=True)
sys.stdin.read()
server.stop()
"""


class CameraLikeCapture:
    """A file read through cv2.VideoCapture that blocks until the next frame is due, like a V4L2 driver."""

    def __init__(self, path: str) -> None:
        self._capture = cv2.VideoCapture(path, cv2.CAP_FFMPEG)
        self._next = time.monotonic()

    def isOpened(self) -> bool:  # noqa: N802 - OpenCV's name
        return self._capture.isOpened()

    def set(self, prop: int, value: float) -> bool:
        return False  # a file grants nothing: the source reports what it actually gets

    def get(self, prop: int) -> float:
        return FPS if prop == cv2.CAP_PROP_FPS else self._capture.get(prop)

    def read(self) -> tuple[bool, np.ndarray | None]:
        self._next += 1 / FPS
        time.sleep(max(0.0, self._next - time.monotonic()))
        ok, image = self._capture.read()
        if not ok:
            self._capture.set(cv2.CAP_PROP_POS_FRAMES, 0)
            ok, image = self._capture.read()
        return ok, image

    def release(self) -> None:
        self._capture.release()


def _clip(folder: Path) -> Path:
    from tests.sources.conftest import create_video_file

    return create_video_file(folder / "bench.mp4", frames=90, width=WIDTH, height=HEIGHT, fps=FPS)


def _circling_pose(t_mono_ns: int) -> PoseAt:
    t = t_mono_ns / 1e9
    return PoseAt(Pose(5 * math.cos(0.2 * t), 5 * math.sin(0.2 * t), -12.0, 2.0, -1.0, math.degrees(0.2 * t) % 360),
                  0.0)


def measure(source: CameraSource, seconds: float) -> dict[str, Any]:
    started = time.monotonic()
    if not source.open():
        return {"error": source.get_properties()["last_error"]}
    open_s = time.monotonic() - started
    try:
        first = source.buffer.wait_newer(0, timeout=10)
        if first is None:
            return {"error": "no frame within 10 s"}
        ages, seq = [], first.seq
        captured0, cpu0, wall0 = source.buffer.captured, time.process_time(), time.monotonic()
        while time.monotonic() - wall0 < seconds:
            frame = source.buffer.wait_newer(seq, timeout=1)
            if frame is None:
                continue
            ages.append(frame.age_s * 1000)
            seq = frame.seq
        cpu, wall, captured = time.process_time() - cpu0, time.monotonic() - wall0, source.buffer.captured - captured0
        props = source.get_properties()
    finally:
        source.close()
    ages.sort()
    return {
        "size": f"{props['width']}x{props['height']}",
        "open_s": round(open_s, 3),
        "delivered_fps": round(len(ages) / wall, 1),
        "cpu_percent_of_one_core": round(100 * cpu / wall, 1),
        "cpu_ms_per_frame": round(1000 * cpu / max(captured, 1), 2),
        "frame_age_ms": {"median": round(statistics.median(ages), 2),
                         "p95": round(ages[int(0.95 * (len(ages) - 1))], 2)} if ages else None,
        "frames_dropped": props["frames_dropped"],
    }


def _serve(kind: str) -> tuple[subprocess.Popen[str], str]:
    server = subprocess.Popen([sys.executable, "-c", SERVER_SCRIPT, kind], cwd=ROOT, text=True,
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                              env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert server.stdout is not None
    return server, server.stdout.readline().strip()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=4.0, help="measuring time per source")
    parser.add_argument("--only", default="", help="comma-separated subset: synthetic,file,usb,sim,rtsp,http")
    args = parser.parse_args()
    wanted = set(filter(None, args.only.split(","))) or {"synthetic", "file", "usb", "sim", "rtsp", "http"}
    results: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as folder:
        clip = str(_clip(Path(folder)))
        local = {
            "synthetic": lambda: create_source(f"synthetic:?width={WIDTH}&height={HEIGHT}&fps={FPS}"),
            "file": lambda: create_source(f"file:{clip}"),
            "usb": lambda: UsbSource.from_uri(SourceUri.parse(f"usb:{clip}?width={WIDTH}&height={HEIGHT}&fps={FPS}"),
                                              capture_factory=CameraLikeCapture),
            "sim": lambda: create_source(f"sim:?width={WIDTH}&height={HEIGHT}&fps={FPS}&targets=2",
                                         pose_provider=_circling_pose),
        }
        for name, make in local.items():
            if name in wanted:
                results[name] = measure(make(), args.seconds)
    for kind in ("rtsp", "http"):
        if kind in wanted:
            server, url = _serve(kind)
            try:
                results[kind] = measure(create_source(url), args.seconds)
            finally:
                server.communicate("", timeout=10)
    print(json.dumps({"benchmark": "sources", "resolution": f"{WIDTH}x{HEIGHT}", "target_fps": FPS,
                      "seconds_per_source": args.seconds, "machine": platform.machine(),
                      "cpus": os.cpu_count(), "python": platform.python_version(),
                      "opencv": cv2.__version__, "sources": results}, indent=2))


if __name__ == "__main__":
    main()
