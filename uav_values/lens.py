"""OpenCV's lens distortion in NumPy: a ray to its pixel as ``cv2.projectPoints`` computes it, and a pixel back to
its undistorted normalised point as ``cv2.undistortPointsIter`` does (the same formulae, the same damped fixed-point
iteration and the same stopping rule), so the camera model needs no OpenCV. ``tests/values/test_lens.py`` checks
both against OpenCV's own.

The coefficients are OpenCV's, in its order: ``(k1, k2, p1, p2[, k3[, k4, k5, k6[, s1, s2, s3, s4[, tau_x,
tau_y]]]])``. A ray ``(X, Y, Z)`` has the normalised point ``x = X/Z, y = Y/Z``; with ``r2 = x^2 + y^2``::

    x'' = x (1 + k1 r2 + k2 r2^2 + k3 r2^3) / (1 + k4 r2 + k5 r2^2 + k6 r2^3) + 2 p1 x y + p2 (r2 + 2 x^2)
          + s1 r2 + s2 r2^2
    y'' = y (same ratio) + p1 (r2 + 2 y^2) + 2 p2 x y + s3 r2 + s4 r2^2

then a tilted sensor's projection (``tau_x``, ``tau_y``: none when both are 0) gives ``(x''', y''')`` and the
pixel is ``(fx x''' + cx, fy y''' + cy)``.

Every function takes one point as floats or many as arrays (N): the same arithmetic, and one point (what a frame
mostly asks for) pays no NumPy call per operation.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from typing import TypeVar

import numpy as np

MAX_ITERATIONS = 30
"""Undistortion stops after this many iterations at most (``cv2.TERM_CRITERIA_COUNT``) ..."""
EPS_PX = 1e-10
"""... or once the point, distorted again, lands within this many pixels of the pixel (``cv2.TERM_CRITERIA_EPS``),
so pixel -> ray -> pixel returns the pixel."""

Coordinate = TypeVar("Coordinate", float, np.ndarray)
"""One point's coordinate (a float) or many points' (an array)."""


@dataclass(frozen=True)
class Lens:
    """A camera's intrinsics (pixels) with OpenCV's distortion coefficients (4, 5, 8, 12 or 14 of them)."""

    fx: float
    fy: float
    cx: float
    cy: float
    coefficients: tuple[float, ...]
    _k: tuple[float, ...] = field(init=False, repr=False, compare=False)
    """The 14 coefficients, zeros where none are given."""
    _tilt: tuple[tuple[float, ...], tuple[float, ...]] | None = field(init=False, repr=False, compare=False)
    """The tilted sensor's projection and its inverse (3x3, by rows), None when the sensor is not tilted."""

    def __post_init__(self) -> None:
        k = (*map(float, self.coefficients), *(0.0,) * (14 - len(self.coefficients)))
        object.__setattr__(self, "_k", k)
        object.__setattr__(self, "_tilt", _tilt_matrices(k[12], k[13]) if k[12] or k[13] else None)

    def project(self, x: Coordinate, y: Coordinate, z: Coordinate) -> tuple[Coordinate, Coordinate]:
        """The pixel ``(u, v)`` the camera-frame ray ``(x, y, z)`` falls on (``z = 0`` is taken as 1, as OpenCV
        does)."""
        inverse_z = _inverse(z)
        return self._pixel(x * inverse_z, y * inverse_z)

    def undistort_point(self, u: float, v: float) -> tuple[float, float]:
        """The undistorted normalised point ``(x, y)`` (its ray is ``(x, y, 1)``) of the pixel ``(u, v)``."""
        x, y = self._start(u, v)
        x0, y0, error, alpha = x, y, sys.float_info.max, 1.0
        for _ in range(MAX_ITERATIONS):
            if error < EPS_PX:
                break
            ratio = self._radial_inverse(x, y)
            if ratio < 0:  # past where the radial function turns back: OpenCV gives the pinhole's point
                return self._pinhole(u, v)
            new_x, new_y = self._step(x, y, x0, y0, ratio, alpha)
            new_error = self._error(new_x, new_y, u, v)
            if new_error > error:
                alpha *= 0.5
            else:
                x, y = new_x, new_y
            error = new_error
        return x, y

    def undistort(self, pixels: np.ndarray) -> np.ndarray:
        """:meth:`undistort_point` of each pixel (N x 2), each iterated until its own stop: N x 2."""
        u, v = np.asarray(pixels, float).reshape(-1, 2).T
        x, y = self._start(u, v)
        x0, y0 = x, y
        error, alpha = np.full(len(u), sys.float_info.max), np.ones(len(u))
        going = np.ones(len(u), bool)
        with np.errstate(all="ignore"):
            for _ in range(MAX_ITERATIONS):
                going &= ~(error < EPS_PX)
                if not going.any():
                    break
                ratio = self._radial_inverse(x, y)
                if (folded := going & (ratio < 0)).any():
                    pinhole_x, pinhole_y = self._pinhole(u, v)
                    x, y = np.where(folded, pinhole_x, x), np.where(folded, pinhole_y, y)
                    going &= ~folded
                new_x, new_y = self._step(x, y, x0, y0, ratio, alpha)
                new_error = self._error(new_x, new_y, u, v)
                worse = new_error > error
                alpha = np.where(going & worse, alpha * 0.5, alpha)
                x, y = np.where(going & ~worse, new_x, x), np.where(going & ~worse, new_y, y)
                error = np.where(going, new_error, error)
        return np.column_stack([x, y])

    def _pixel(self, x: Coordinate, y: Coordinate) -> tuple[Coordinate, Coordinate]:
        """The pixel of the undistorted normalised point ``(x, y)``: the formula above."""
        k = self._k
        r2 = x * x + y * y
        r4 = r2 * r2
        radial = 1 + k[0] * r2 + k[1] * r4 + k[4] * (r4 * r2)
        inverse = 1.0 / (1 + k[5] * r2 + k[6] * r4 + k[7] * (r4 * r2))
        xd = x * radial * inverse + k[2] * (2 * x * y) + k[3] * (r2 + 2 * x * x) + k[8] * r2 + k[9] * r4
        yd = y * radial * inverse + k[2] * (r2 + 2 * y * y) + k[3] * (2 * x * y) + k[10] * r2 + k[11] * r4
        if self._tilt is not None:
            xd, yd = _apply(self._tilt[0], xd, yd)
        return xd * self.fx + self.cx, yd * self.fy + self.cy

    def _pinhole(self, u: Coordinate, v: Coordinate) -> tuple[Coordinate, Coordinate]:
        """The normalised point of pixel ``(u, v)`` with no distortion."""
        return (u - self.cx) * (1.0 / self.fx), (v - self.cy) * (1.0 / self.fy)

    def _start(self, u: Coordinate, v: Coordinate) -> tuple[Coordinate, Coordinate]:
        """The distorted normalised point of pixel ``(u, v)``, the sensor's tilt removed: where iteration starts."""
        x, y = self._pinhole(u, v)
        return (x, y) if self._tilt is None else _apply(self._tilt[1], x, y)

    def _radial_inverse(self, x: Coordinate, y: Coordinate) -> Coordinate:
        """The radial ratio's inverse at ``(x, y)``; negative past where the radial function turns back."""
        k = self._k
        r2 = x * x + y * y
        ratio: Coordinate = (1 + ((k[7] * r2 + k[6]) * r2 + k[5]) * r2) / (1 + ((k[4] * r2 + k[1]) * r2 + k[0]) * r2)
        return ratio

    def _step(self, x: Coordinate, y: Coordinate, x0: Coordinate, y0: Coordinate, ratio: Coordinate,
              alpha: Coordinate) -> tuple[Coordinate, Coordinate]:
        """One damped fixed-point step from ``(x, y)`` towards the point that distorts to ``(x0, y0)``."""
        k = self._k
        r2 = x * x + y * y
        delta_x = 2 * k[2] * x * y + k[3] * (r2 + 2 * x * x) + k[8] * r2 + k[9] * r2 * r2
        delta_y = k[2] * (r2 + 2 * y * y) + 2 * k[3] * x * y + k[10] * r2 + k[11] * r2 * r2
        return ((1 - alpha) * x + alpha * (x0 - delta_x) * ratio, (1 - alpha) * y + alpha * (y0 - delta_y) * ratio)

    def _error(self, x: Coordinate, y: Coordinate, u: Coordinate, v: Coordinate) -> Coordinate:
        """How far (pixels) the point ``(x, y)``, distorted again, lands from the pixel ``(u, v)``."""
        pu, pv = self._pixel(x, y)
        du, dv = pu - u, pv - v
        error: Coordinate = (du * du + dv * dv) ** 0.5  # (a float's ** 2 raises where C overflows to inf)
        return error


def _tilt_matrices(tau_x: float, tau_y: float) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The tilted sensor's projection and its inverse, by rows, as OpenCV's ``computeTiltProjectionMatrix``."""
    cx, sx, cy, sy = math.cos(tau_x), math.sin(tau_x), math.cos(tau_y), math.sin(tau_y)
    rotation = np.array([[cy, 0, -sy], [0, 1, 0], [sy, 0, cy]]) @ np.array([[1, 0, 0], [0, cx, sx], [0, -sx, cx]])
    (_, _, r02), (_, _, r12), (_, _, r22) = rotation
    projection = np.array([[r22, 0, -r02], [0, r22, -r12], [0, 0, 1]]) @ rotation
    inv = 1 / r22
    inverse = rotation.T @ np.array([[inv, 0, inv * r02], [0, inv, inv * r12], [0, 0, 1]])
    return tuple(projection.ravel().tolist()), tuple(inverse.ravel().tolist())


def _apply(matrix: tuple[float, ...], x: Coordinate, y: Coordinate) -> tuple[Coordinate, Coordinate]:
    """The point ``(x, y, 1)`` through the 3x3 ``matrix`` (by rows), back on the plane z = 1."""
    m = matrix
    scale = _inverse(m[6] * x + m[7] * y + m[8])
    return scale * (m[0] * x + m[1] * y + m[2]), scale * (m[3] * x + m[4] * y + m[5])


def _inverse(value: Coordinate) -> Coordinate:
    """``1 / value``, and 1 where ``value`` is 0 (OpenCV's guard: such a point keeps its coordinates)."""
    if isinstance(value, np.ndarray):
        inverse: np.ndarray = np.divide(1.0, value, out=np.ones_like(value, float), where=value != 0)
        return inverse
    return 1.0 / value if value else 1.0
