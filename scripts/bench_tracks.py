"""The platform's tracks over a processor's detections (issue 50): what they cost a frame against the detector, and
how well they keep ids.

Cost: :meth:`uav_tui.hosting.tracks.DetectionTracks.assign` (the checked detections into ByteTrack and back, each
with its ``track_id``) for 3, 10 and 32 (the most a processor may report) detections drifting a pixel a frame,
against the shipped ``yolo`` processor's detector (Yolo-Fastest on OpenCV's Darknet loader) on a 640x480 ``sim:``
frame. Issue 50's goal: the tracker under 10 % of the detector a frame.
Ids: the ``sim:`` camera's three cars crossing, seen by a detector that reports their true boxes with 1.5 px noise
and nothing for 1 s while two of them cross (tests/hosting/sim_cars.py), at 5 to 30 detections a second: the ids
each car had beyond its first (0 is perfect), with the platform's settings and with the library's defaults.

Usage: python scripts/bench_tracks.py > scripts/results/tracks.json
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from processors.detection import DetectorConfig, load_backend  # noqa: E402
from sources.ground import default_ground  # noqa: E402
from sources.sim_camera import SimCameraSource  # noqa: E402
from sources.sim_geometry import Pose  # noqa: E402
from sources.sim_render import SimRenderer  # noqa: E402
from sources.uri import SourceUri  # noqa: E402
from tests.hosting.sim_cars import track_ids  # noqa: E402
from uav_tui.hosting import tracks  # noqa: E402
from uav_values.detections import Detected  # noqa: E402

FRAMES = 2000
GOAL_SHARE = 0.10
LIBRARY_DEFAULTS = {"MATCH_IOU": 0.25, "KALMAN_UPDATE": 0.25, "KEEP_LOST_S": 0.5}
"""edgefirst-tracker's ByteTrack defaults, for comparison."""


def tracker_ms(count: int) -> dict[str, float]:
    rng = np.random.default_rng(0)
    corners = rng.uniform(0, 560, (count, 2))
    sizes = rng.uniform(20, 80, (count, 2))
    frames = [tuple(Detected((round(x + i), round(y), round(w), round(h)), "car", 0.9)
                    for (x, y), (w, h) in zip(corners, sizes, strict=True)) for i in range(FRAMES)]
    tracker, times = tracks.DetectionTracks(), []
    for i, found in enumerate(frames):
        start = time.perf_counter()
        tracker.assign(found, i * 33_333_333)
        times.append((time.perf_counter() - start) * 1000)
    return {"p50_ms": round(statistics.median(times), 4), "p95_ms": round(float(np.percentile(times, 95)), 4)}


def detector_ms() -> float:
    source = SimCameraSource.from_uri(SourceUri.parse("sim:?targets=3"))
    frame = SimRenderer(source.camera, default_ground(0), source.targets, 2.0).render(Pose(d=-30.0), 1.0)
    backend = load_backend(None, DetectorConfig(0.25, 0.45, None))
    backend.detect(frame)  # warm
    times = []
    for _ in range(20):
        start = time.perf_counter()
        backend.detect(frame)
        times.append((time.perf_counter() - start) * 1000)
    return round(statistics.median(times), 2)


def extra_ids(fps: float) -> int:
    total = 0
    for seed in (1, 2, 3):
        ids, _ = track_ids(fps, tracks.DetectionTracks(), seed)
        total += sum(len(set(seen)) - 1 for seen in ids.values())
    return total


def ids_kept() -> dict[str, Any]:
    rates = (5, 10, 15, 30)
    platform_ids = {f"{fps}_fps": extra_ids(fps) for fps in rates}
    kept = {name: getattr(tracks, name) for name in LIBRARY_DEFAULTS}
    for name, value in LIBRARY_DEFAULTS.items():
        setattr(tracks, name, value)
    try:
        library_ids = {f"{fps}_fps": extra_ids(fps) for fps in rates}
    finally:
        for name, value in kept.items():
            setattr(tracks, name, value)
    return {"platform": {**kept, "extra_ids_3_seeds": platform_ids},
            "library_defaults": {**LIBRARY_DEFAULTS, "extra_ids_3_seeds": library_ids}}


def main() -> None:
    costs = {f"{count}_detections": tracker_ms(count) for count in (3, 10, 32)}
    detector = detector_ms()
    worst = costs["32_detections"]["p50_ms"]
    print(json.dumps({
        "machine": {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
                    "load_1min": round(os.getloadavg()[0], 2)},
        "tracker_per_frame": costs,
        "detector_per_frame_ms": {"yolo_fastest_darknet_640x480": detector},
        "tracker_share_of_detector_at_32": round(worst / detector, 4),
        "goal_share": GOAL_SHARE, "goal_met": worst / detector < GOAL_SHARE,
        "ids_through_crossing_and_1s_gap": ids_kept(),
    }, indent=2))


if __name__ == "__main__":
    main()
