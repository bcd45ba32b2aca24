"""Detection at 640x480 on real aerial video: the shipped Yolo-Fastest on OpenCV DNN and on ONNX Runtime (issue 50).

For each runtime, the ``yolo`` processor (:class:`processors.yolo_detector.YoloDetector`, the shipped model at its
320-px input) runs over the same decoded frames, detecting on every frame (``detect_every=1``) and on every 3rd with
optical flow between (``detect_every=3``, its ``fast`` mode). Per configuration: frames a second (wall time of
``photo_processing``, the frame's copy included) and CPU seconds a frame (``time.process_time``: every thread of
the process, OpenCV's and ONNX Runtime's workers too). Then the platform's tracker
(:meth:`uav_tui.hosting.tracks.DetectionTracks.assign`) on each frame's checked detections: its CPU a frame and its
share of the processor's (issue 50's goal: under 10 %). Each configuration runs ``ROUNDS`` times, interleaved, and
the round with the least CPU a frame is kept (the machine is shared: that one was disturbed least). ``load_s``:
opening the detector in a fresh process (imports of ``onnx`` / ``onnxruntime`` included), ONNX Runtime's first
start (conversion, with an empty cache folder) and its later ones (the cached graph).

Usage: nice -n 10 .venv/bin/python scripts/bench_detection.py > scripts/results/detection.json
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from processors.detection import find_data_dir  # noqa: E402
from processors.detections import read_detections  # noqa: E402
from processors.yolo_detector import YoloDetector  # noqa: E402
from uav_tui.hosting.tracks import DetectionTracks  # noqa: E402

RUNTIMES = ("opencv", "onnxruntime")
"""Darknet-on-OpenCV first: the one to beat."""
SIZE = (640, 480)
SEQUENCES = ("uavdt-S1606", "dtb70-Animal3", "uav123_10fps-person9", "uav123_10fps-boat5")
"""Cars at a crossroads, a herd, two people, a boat: many, several, few and one detection a frame."""
FRAMES_EACH = 60
DETECT_EVERY = (1, 3)
ROUNDS = 3
WARM_UP = 5
FRAME_NS = 33_333_333
"""The tracker sees the frames 30 a second apart."""
GOAL_SHARE = 0.10

LOAD = """
import sys, time
from processors.detection import DetectorConfig, load_backend
start = time.perf_counter()
load_backend(None, DetectorConfig(), sys.argv[1])
print(time.perf_counter() - start)
"""
"""Opens the shipped detector with the runtime of argv[1] and prints the seconds it took."""


def real_frames() -> list[np.ndarray]:
    """The first ``FRAMES_EACH`` frames of each of ``SEQUENCES``, resized to ``SIZE``."""
    frames = []
    for name in SEQUENCES:
        capture = cv2.VideoCapture(str(find_data_dir() / "aerial-tracking" / name / "video.mp4"))
        for _ in range(FRAMES_EACH):
            ok, frame = capture.read()
            if not ok:
                break
            frames.append(cv2.resize(frame, SIZE, interpolation=cv2.INTER_AREA))
        capture.release()
    return frames


def run(runtime: str, every: int, frames: list[np.ndarray]) -> dict[str, Any]:
    """One pass of the processor over ``frames``, then of the tracker over what it reported."""
    detector = YoloDetector(runtime=runtime, detect_every=every)
    for frame in frames[:WARM_UP]:
        detector.backend.detect(frame)  # the network's first runs allocate; the processor's state stays new
    seen = []
    cpu, wall = time.process_time(), time.perf_counter()
    for frame in frames:
        detector.photo_processing(frame.copy())
        seen.append(detector.detections)
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    reported = [read_detections(SimpleNamespace(detections=detections)) for detections in seen]  # the platform's check
    tracks = DetectionTracks()
    tracker_cpu = time.process_time()
    for i, found in enumerate(reported):
        tracks.assign(found, i * FRAME_NS)
    tracker_cpu = time.process_time() - tracker_cpu
    per_frame = cpu / len(frames)
    return {"fps": round(len(frames) / wall, 1), "cpu_s_per_frame": round(per_frame, 5),
            "detections_per_frame": round(sum(len(r or ()) for r in reported) / len(frames), 2),
            "tracker_cpu_s_per_frame": round(tracker_cpu / len(frames), 6),
            "tracker_share_of_detector": round(tracker_cpu / len(frames) / per_frame, 4)}


def load_seconds() -> dict[str, float]:
    """Seconds to open the detector in a fresh process: OpenCV DNN, ONNX Runtime first (empty cache), cached."""
    def timed(runtime: str, cache: str) -> float:
        done = subprocess.run([sys.executable, "-c", LOAD, runtime], capture_output=True, text=True, check=True,
                              cwd=ROOT, env={**os.environ, "XDG_CACHE_HOME": cache})
        return round(float(done.stdout.strip()), 3)

    with tempfile.TemporaryDirectory() as cache:
        return {"opencv": timed("opencv", cache), "onnxruntime_first": timed("onnxruntime", cache),
                "onnxruntime_cached": timed("onnxruntime", cache)}


def main() -> None:
    import onnxruntime

    frames = real_frames()
    best: dict[str, dict[str, Any]] = {}
    for _ in range(ROUNDS):
        for every in DETECT_EVERY:
            for runtime in RUNTIMES:
                name = f"{runtime}_every_{every}"
                result = run(runtime, every, frames)
                if name not in best or result["cpu_s_per_frame"] < best[name]["cpu_s_per_frame"]:
                    best[name] = result
    ratio = {f"every_{every}": round(best[f"opencv_every_{every}"]["cpu_s_per_frame"]
                                     / best[f"onnxruntime_every_{every}"]["cpu_s_per_frame"], 2)
             for every in DETECT_EVERY}
    worst_share = max(result["tracker_share_of_detector"] for result in best.values())
    print(json.dumps({
        "benchmark": "detection",
        "machine": {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
                    "opencv": cv2.__version__, "opencv_threads": cv2.getNumThreads(),
                    "onnxruntime": onnxruntime.__version__, "load_average_1min_at_end": round(os.getloadavg()[0], 2)},
        "frames": len(frames), "size": f"{SIZE[0]}x{SIZE[1]}", "sequences": list(SEQUENCES), "rounds": ROUNDS,
        "runs": best,
        "opencv_cpu_over_onnxruntime_cpu": ratio,
        "load_s": load_seconds(),
        "goal_tracker_share": GOAL_SHARE, "goal_tracker_share_met": worst_share < GOAL_SHARE,
    }, indent=2))


if __name__ == "__main__":
    main()
