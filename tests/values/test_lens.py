"""The camera model's distortion in NumPy (``uav_values.lens``) gives what OpenCV gives: pixels to rays as
``cv2.undistortPointsIter`` with the same stopping rule, rays to pixels as ``cv2.projectPoints``, for the one-point
and the many-point calls, over the whole frame."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from tests.sources.test_camera_model import BARREL
from uav_values.camera import CameraModel
from uav_values.lens import EPS_PX, MAX_ITERATIONS, Lens

MODELS = {
    # The tests' calibration file (tests/sources/test_camera_model.py: SAMPLE_YAML) and the benchmarks' lens.
    "test-calibration-file": CameraModel(640, 480, 505.12, 504.88, 318.75, 242.10, BARREL),
    "bench-barrel": CameraModel(640, 480, 505.1, 504.9, 318.7, 242.1, (-0.28, 0.09, 0.0008, -0.0005, 0.0)),
    # OpenCV's own sample calibration (samples/data/left_intrinsics.yml, the left01..14.jpg board views).
    "opencv-sample-left": CameraModel(640, 480, 535.91573396163199, 535.91573396163199, 342.28315473308373,
                                      235.57082909788173, (-0.26637260909660682, -0.038588898922304653,
                                                           0.0017831947042852964, -0.00028122100441115472,
                                                           0.23839153080878486)),
    # Four coefficients, and OpenCV's rational, thin-prism and tilted-sensor models (8, 12 and 14).
    "four": CameraModel(1280, 720, 910.0, 908.0, 641.0, 362.0, (-0.12, 0.03, 0.0006, -0.0009)),
    "rational": CameraModel(640, 480, 505.1, 504.9, 318.7, 242.1, (0.5, -0.1, 0.001, -0.002, 0.01, 0.8, -0.05, 0.02)),
    "thin-prism": CameraModel(640, 480, 505.1, 504.9, 318.7, 242.1, (-0.2, 0.05, 0.001, -0.001, 0.0, 0.0, 0.0, 0.0,
                                                                      0.002, -0.001, 0.001, 0.0005)),
    "tilted": CameraModel(640, 480, 505.1, 504.9, 318.7, 242.1, (-0.2, 0.05, 0.001, -0.001, 0.0, 0.0, 0.0, 0.0, 0.002,
                                                                  -0.001, 0.001, 0.0005, 0.01, -0.02)),
}
CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, MAX_ITERATIONS, EPS_PX)
"""OpenCV's stopping rule as the lens states it."""


def over_the_frame(model: CameraModel, count: int, margin: float = 0.0) -> np.ndarray:
    """``count`` random pixels over the frame (``margin``: a share of its size beyond each edge) and its corners."""
    size = np.array([model.width - 1, model.height - 1], float)
    corners = np.array([(0, 0), (1, 0), (0, 1), (1, 1)]) * size
    pixels = np.random.default_rng(7).uniform(-margin * size, (1 + margin) * size, (count, 2))
    return np.vstack([corners, pixels])


def opencv_undistorted(model: CameraModel, pixels: np.ndarray) -> np.ndarray:
    return cv2.undistortPointsIter(pixels.reshape(-1, 1, 2), model.matrix, model.distortion_array, None, None,
                                   CRITERIA).reshape(-1, 2)


@pytest.mark.parametrize("model", MODELS.values(), ids=MODELS.keys())
def test_pixels_undistort_as_opencv_undistorts_them(model: CameraModel) -> None:
    pixels = over_the_frame(model, 2000)
    expected = opencv_undistorted(model, pixels)
    rays = model.pixels_to_rays(pixels)
    assert np.abs(rays[:, :2] / rays[:, 2:] - expected).max() < 1e-9  # normalised units
    one_by_one = np.array([model.pixel_to_ray(u, v) for u, v in pixels[:200]])
    assert np.abs(one_by_one[:, :2] / one_by_one[:, 2:] - expected[:200]).max() < 1e-9


@pytest.mark.parametrize("model", MODELS.values(), ids=MODELS.keys())
def test_rays_project_as_opencv_projects_them(model: CameraModel) -> None:
    """Rays towards the frame and 20 % beyond each edge, of any length."""
    pinhole = (over_the_frame(model, 2000, margin=0.2) - (model.cx, model.cy)) / (model.fx, model.fy)
    lengths = np.random.default_rng(8).uniform(0.1, 50.0, (len(pinhole), 1))
    rays = np.column_stack([pinhole, np.ones(len(pinhole))]) * lengths
    projected, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), model.matrix, model.distortion_array)
    expected = projected.reshape(-1, 2)
    assert np.abs(model.rays_to_pixels(rays) - expected).max() < 1e-6  # pixels
    one_by_one = np.array([model.ray_to_pixel(ray) for ray in rays[:200]])
    assert np.abs(one_by_one - expected[:200]).max() < 1e-6


def test_a_lens_past_its_fold_undistorts_as_opencv_does() -> None:
    """Far outside what a camera model takes (its radial function turns back inside the image): OpenCV's damped
    steps, its iteration cap and its fallback to the pinhole's point where the radial ratio turns negative."""
    lens = Lens(300.0, 300.0, 320.0, 240.0, (-0.9, 0.5, 0.01, 0.0, -0.1))
    matrix = np.array([[300.0, 0.0, 320.0], [0.0, 300.0, 240.0], [0.0, 0.0, 1.0]])
    pixels = np.random.default_rng(9).uniform((-300, -300), (940, 780), (3000, 2))
    expected = cv2.undistortPointsIter(pixels.reshape(-1, 1, 2), matrix, np.array(lens.coefficients), None, None,
                                       CRITERIA).reshape(-1, 2)
    pinhole = (pixels - (320.0, 240.0)) / 300.0
    assert 100 < np.all(expected == pinhole, axis=1).sum() < len(pixels) - 100  # both ways are taken
    assert np.abs(lens.undistort(pixels) - expected).max() < 1e-9
    one_by_one = np.array([lens.undistort_point(u, v) for u, v in pixels[:300]])
    assert np.abs(one_by_one - expected[:300]).max() < 1e-9

