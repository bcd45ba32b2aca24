"""OpenCV camera calibration files and calibration from board views, as OpenCV's calibration samples do them.

The file is what ``cv2.FileStorage`` writes (YAML, JSON or XML by its extension) with the sample's keys:
``image_width``, ``image_height``, ``camera_matrix``, ``distortion_coefficients`` and
``avg_reprojection_error``; files from OpenCV's ``calibration.cpp`` / ``camera_calibration.cpp`` load as they are.
"""

from __future__ import annotations

import math
import os
import re
import time
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from sources.calibration_boards import Board, View
from sources.calibration_views import coverage_problem
from uav_values.camera import CameraModel, CameraModelError, Mount

MAX_FILE_BYTES = 1_000_000
"""A calibration file is a few hundred bytes; anything far larger is not one."""
MAKE_ONE = "make one with: uav-tui calibrate --source URI --out FILE"
MAX_UNCERTAINTY = 0.02
"""The largest 1-sigma uncertainty OpenCV may report for fx and fy (share of the value) and for cx and cy (share
of the image's size); good views of a flat board give about 0.2 %."""
AGAIN = ("show the board in more places and tilts (near and far, all over the image, tilted up to about 45 degrees "
         "each way), then calibrate again")


@dataclass(frozen=True)
class Calibration:
    """What calibration found: image size, K, distortion, RMS reprojection error (px) and the views used."""

    width: int
    height: int
    matrix: np.ndarray
    distortion: np.ndarray
    rms_px: float | None = None
    views: int = 0

    def model(self, mount: Mount | None = None, origin: str = "") -> CameraModel:
        k = self.matrix
        return CameraModel(self.width, self.height, float(k[0, 0]), float(k[1, 1]), float(k[0, 2]), float(k[1, 2]),
                           tuple(float(c) for c in self.distortion.ravel()), mount or Mount(), origin, self.rms_px)


def load_model(path: str | Path, mount: Mount | None = None) -> CameraModel:
    """The camera model in calibration file ``path``, mounted by ``mount``; CameraModelError says what to do."""
    return read_calibration(path).model(mount, f"calibration file {path}")


def read_calibration(path: str | Path) -> Calibration:
    """Read an OpenCV calibration file; CameraModelError names the problem and what to do."""
    path = Path(path).expanduser()
    if not path.is_file():
        raise CameraModelError(f"calibration file {path} does not exist; {MAKE_ONE}")
    if path.stat().st_size > MAX_FILE_BYTES:
        raise CameraModelError(f"calibration file {path} is {path.stat().st_size} bytes, not a calibration file "
                               f"(they are under 1 kB); {MAKE_ONE}")
    bad = (f"calibration file {path} is not an OpenCV calibration file (the YAML, JSON or XML cv2.FileStorage writes, "
           f"with camera_matrix, distortion_coefficients, image_width, image_height)")
    try:
        storage = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    except (cv2.error, SystemError) as exc:  # OpenCV's parse error, sometimes wrapped in a SystemError
        cause = exc.__cause__ or exc.__context__ or exc
        text = (str(cause).strip().splitlines() or [""])[-1]
        reason = re.sub(r"^.*error: \([^)]*\) ", "", text).strip()[:200] or "parse error"
        raise CameraModelError(f"{bad}: {reason}; {MAKE_ONE}") from None
    try:
        if not storage.isOpened():
            raise CameraModelError(f"{bad}; {MAKE_ONE}")
        nodes = {name: storage.getNode(name) for name in ("camera_matrix", "distortion_coefficients", "image_width",
                                                           "image_height", "avg_reprojection_error")}
        missing = [name for name, node in list(nodes.items())[:4] if node.empty()]
        if missing:
            raise CameraModelError(f"{bad}: {', '.join(missing)} missing; {MAKE_ONE}")
        matrix, distortion = nodes["camera_matrix"].mat(), nodes["distortion_coefficients"].mat()
        width, height = nodes["image_width"].real(), nodes["image_height"].real()
        rms = nodes["avg_reprojection_error"].real() if nodes["avg_reprojection_error"].isReal() else None
    finally:
        storage.release()
    if matrix is None or matrix.shape != (3, 3) or distortion is None or distortion.size not in (4, 5, 8, 12, 14):
        raise CameraModelError(f"{bad}: camera_matrix must be 3x3 and distortion_coefficients 4, 5, 8, 12 or 14 "
                               f"numbers; {MAKE_ONE}")
    if not (width >= 1 and height >= 1 and width == int(width) and height == int(height)):
        raise CameraModelError(f"{bad}: image_width and image_height must be whole numbers of pixels; {MAKE_ONE}")
    try:
        calibration = Calibration(int(width), int(height), matrix.astype(float), distortion.astype(float).ravel(),
                                  rms if rms is not None and math.isfinite(rms) else None)
        calibration.model()  # the checks of the model: positive, finite focal lengths
    except CameraModelError as exc:
        raise CameraModelError(f"calibration file {path}: {exc}; {MAKE_ONE}") from None
    return calibration


def write_calibration(path: str | Path, calibration: Calibration, board: Board) -> None:
    """Write ``calibration`` as OpenCV's sample does (format by the extension: .yaml/.yml, .json or .xml)."""
    path = Path(path).expanduser()
    partial = path.with_name(f".{path.stem}.partial{path.suffix}")
    storage = cv2.FileStorage(str(partial), cv2.FILE_STORAGE_WRITE)
    try:
        storage.write("calibration_time", time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()))
        storage.write("nr_of_frames", calibration.views)
        storage.write("image_width", calibration.width)
        storage.write("image_height", calibration.height)
        for name, value in board.file_fields().items():
            storage.write(name, value)
        storage.write("camera_matrix", calibration.matrix)
        storage.write("distortion_coefficients", calibration.distortion.reshape(-1, 1))
        if calibration.rms_px is not None:
            storage.write("avg_reprojection_error", calibration.rms_px)
    finally:
        storage.release()
    os.replace(partial, path)


def calibrate(views: list[View], size: tuple[int, int]) -> Calibration:
    """``cv2.calibrateCameraExtended`` over ``views`` (each from a board's ``find``) of frames of ``size`` = (width,
    height); CameraModelError (saying what to do) when the views cannot constrain it.

    Fits k1, k2, p1, p2 (k3 fixed at 0, as the samples advise for ordinary lenses: it overfits with few views).
    Refused: views that are not tilted or not spread (:func:`~sources.calibration_views.coverage_problem`), a
    result whose intrinsics OpenCV itself reports uncertain by more than :data:`MAX_UNCERTAINTY`, and one that
    is not a camera (:mod:`uav_values.camera_plausibility`).
    """
    if len(views) < 3:
        raise CameraModelError(f"calibration needs at least 3 views of the board, got {len(views)}")
    if problem := coverage_problem(views, size):
        raise CameraModelError(f"nothing written: {problem}")
    objects, points = [objects for objects, _ in views], [points for _, points in views]
    try:
        rms, matrix, distortion, _, _, deviations, _, _ = cv2.calibrateCameraExtended(
            objects, points, size, np.eye(3), np.zeros(5), flags=cv2.CALIB_FIX_K3)  # no guess: both ignored
    except cv2.error:
        raise CameraModelError(f"cv2.calibrateCamera found no solution in {len(views)} views: {AGAIN}") from None
    fx, fy, cx, cy = (float(v) for v in deviations.ravel()[:4])
    shares = {"fx": fx / matrix[0, 0], "fy": fy / matrix[1, 1], "cx": cx / size[0], "cy": cy / size[1]}
    if uncertain := [f"{name} +-{share:.1%}" for name, share in shares.items() if not share <= MAX_UNCERTAINTY]:
        raise CameraModelError(f"nothing written: the views leave the intrinsics uncertain ({', '.join(uncertain)}; "
                               f"at most {MAX_UNCERTAINTY:.0%} is taken: blurred corners, or too few views): {AGAIN}")
    calibration = Calibration(size[0], size[1], matrix, distortion.ravel(), float(rms), len(views))
    try:
        calibration.model()
    except CameraModelError as exc:
        raise CameraModelError(f"nothing written: the views give no camera ({exc}): {AGAIN}") from None
    return calibration
