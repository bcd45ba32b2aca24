"""Cost of the camera model's calls, per call, as a processor or the platform makes them (one pixel a frame, or
a few hundred points at once); pinhole (sim:, camera_hfov) and with distortion (a calibration file). Then the
distortion alone, NumPy (``uav_values.lens``, what the model uses) against OpenCV (``cv2.undistortPointsIter``
and ``cv2.projectPoints``, what it used before) for one point and for 1000.

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

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from uav_values.camera import CameraModel  # noqa: E402
from uav_values.lens import EPS_PX, MAX_ITERATIONS, Lens  # noqa: E402

BARREL = (-0.28, 0.09, 0.0008, -0.0005, 0.0)
CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, MAX_ITERATIONS, EPS_PX)


def per_call_us(call, repeat: int) -> dict[str, float]:
    """p50 and p95 of ``repeat`` calls, each timed alone, in microseconds."""
    times = np.empty(repeat)
    for i in range(repeat):
        start = time.perf_counter_ns()
        call()
        times[i] = time.perf_counter_ns() - start
    return {"p50_us": round(float(np.percentile(times, 50)) / 1e3, 2),
            "p95_us": round(float(np.percentile(times, 95)) / 1e3, 2)}


def model_calls(repeat: int) -> dict[str, dict[str, dict[str, float]]]:
    points = np.random.default_rng(0).uniform((0, 0), (640, 480), size=(300, 2))
    results = {}
    for name, model in (("pinhole", CameraModel.from_hfov(640, 480, 62.0)),
                        ("distorted", CameraModel(640, 480, 505.1, 504.9, 318.7, 242.1, BARREL))):
        ray = model.pixel_to_ray(100.0, 200.0)
        rays = model.pixels_to_rays(points)
        results[name] = {
            "pixel_to_ray": per_call_us(lambda m=model: m.pixel_to_ray(100.0, 200.0), repeat),
            "ray_to_pixel": per_call_us(lambda m=model, r=ray: m.ray_to_pixel(r), repeat),
            "ray_in_body": per_call_us(lambda m=model, r=ray: m.ray_in_body(r), repeat),
            "pixels_to_rays_300": per_call_us(lambda m=model: m.pixels_to_rays(points), repeat // 10),
            "rays_to_pixels_300": per_call_us(lambda m=model, r=rays: m.rays_to_pixels(r), repeat // 10),
        }
    return results


def against_opencv(repeat: int) -> dict[str, dict[str, dict[str, float]]]:
    """The distortion step alone (the calibration file's lens), one point and 1000 over the frame."""
    lens = Lens(505.1, 504.9, 318.7, 242.1, BARREL)
    k, d = np.array([[505.1, 0.0, 318.7], [0.0, 504.9, 242.1], [0.0, 0.0, 1.0]]), np.array(BARREL)
    pixels = np.random.default_rng(1).uniform((0, 0), (640, 480), size=(1000, 2))
    one = np.array([[[100.0, 200.0]]])
    normalised = lens.undistort(pixels)
    rays = np.column_stack([normalised, np.ones(len(normalised))])
    ray, no_turn = rays[:1].copy(), np.zeros(3)
    x, y, z = (float(c) for c in ray[0])
    return {
        "undistort_1": {
            "numpy": per_call_us(lambda: lens.undistort_point(100.0, 200.0), repeat),
            "opencv": per_call_us(lambda: cv2.undistortPointsIter(one, k, d, None, None, CRITERIA), repeat)},
        "undistort_1000": {
            "numpy": per_call_us(lambda: lens.undistort(pixels), repeat // 100),
            "opencv": per_call_us(lambda: cv2.undistortPointsIter(pixels.reshape(-1, 1, 2), k, d, None, None,
                                                                  CRITERIA), repeat // 100)},
        "project_1": {
            "numpy": per_call_us(lambda: lens.project(x, y, z), repeat),
            "opencv": per_call_us(lambda: cv2.projectPoints(ray, no_turn, no_turn, k, d), repeat)},
        "project_1000": {
            "numpy": per_call_us(lambda: lens.project(rays[:, 0], rays[:, 1], rays[:, 2]), repeat // 100),
            "opencv": per_call_us(lambda: cv2.projectPoints(rays, no_turn, no_turn, k, d), repeat // 100)},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=20000)
    args = parser.parse_args()
    print(json.dumps({"bench": "camera_model", "machine": platform.machine(), "python": platform.python_version(),
                      "opencv": cv2.__version__, "numpy": np.__version__, "repeat": args.repeat,
                      **model_calls(args.repeat), "distortion_numpy_vs_opencv": against_opencv(args.repeat)},
                     indent=1))


if __name__ == "__main__":
    main()
