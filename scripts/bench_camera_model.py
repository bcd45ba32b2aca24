"""Cost of the camera model's calls, per call, as a processor or the platform makes them (one pixel a frame, or
a few hundred points at once); pinhole (sim:, camera_hfov) and with distortion (a calibration file).

Issue 39's goal for the whole geo-location projection is <= 0.1 ms a frame; the pixel -> ray step is part of it.

Usage: python scripts/bench_camera_model.py [--repeat 20000]
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sources.camera_model import CameraModel  # noqa: E402

BARREL = (-0.28, 0.09, 0.0008, -0.0005, 0.0)


def per_call_us(call, repeat: int) -> dict[str, float]:
    """p50 and p95 of ``repeat`` calls, each timed alone, in microseconds."""
    times = np.empty(repeat)
    for i in range(repeat):
        start = time.perf_counter_ns()
        call()
        times[i] = time.perf_counter_ns() - start
    return {"p50_us": round(float(np.percentile(times, 50)) / 1e3, 2),
            "p95_us": round(float(np.percentile(times, 95)) / 1e3, 2)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=20000)
    args = parser.parse_args()
    points = np.random.default_rng(0).uniform((0, 0), (640, 480), size=(300, 2))
    results = {}
    for name, model in (("pinhole", CameraModel.from_hfov(640, 480, 62.0)),
                        ("distorted", CameraModel(640, 480, 505.1, 504.9, 318.7, 242.1, BARREL))):
        ray = model.pixel_to_ray(100.0, 200.0)
        rays = model.pixels_to_rays(points)
        results[name] = {
            "pixel_to_ray": per_call_us(lambda m=model: m.pixel_to_ray(100.0, 200.0), args.repeat),
            "ray_to_pixel": per_call_us(lambda m=model, r=ray: m.ray_to_pixel(r), args.repeat),
            "ray_in_body": per_call_us(lambda m=model, r=ray: m.ray_in_body(r), args.repeat),
            "pixels_to_rays_300": per_call_us(lambda m=model: m.pixels_to_rays(points), args.repeat // 10),
            "rays_to_pixels_300": per_call_us(lambda m=model, r=rays: m.rays_to_pixels(r), args.repeat // 10),
        }
    print(json.dumps({"bench": "camera_model", "machine": platform.machine(), "python": platform.python_version(),
                      "repeat": args.repeat, **results}, indent=1))


if __name__ == "__main__":
    main()
