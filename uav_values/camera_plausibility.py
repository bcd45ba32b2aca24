"""Whether a camera model's numbers can be a camera at all: its field of view, its principal point, and a lens
distortion that keeps the image one-to-one.

A calibration file is data from outside (edited, damaged, or the result of views that did not constrain it): a
focal length of 1e-6 or 1e12 px, a principal point a million pixels away or ``k3 = 1e9`` are finite, positive
numbers that describe no lens, and would send every ray (geo-location, landing targets) somewhere impossible.

The distortion's radial function ``r_d(r) = r (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6)``
(normalized radius, undistorted -> distorted) must rise all the way from the image's centre to its farthest
corner: where it turns back, two rays land on one pixel and undistorting a pixel has no single answer. The field of
view is measured through the distortion (the rays the image's edges see), not the pinhole's alone.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

MIN_HFOV_DEG = 1.0
"""Narrowest horizontal field of view taken (a 30x zoom camera at its long end sees about 2 degrees)."""
MAX_FOV_DEG = 175.0
"""Widest field of view the pinhole-with-distortion model can describe (a fisheye beyond needs another model)."""
MAX_ASPECT = 2.0
"""fy / fx within 1/2..2: pixels are about square on any camera a drone carries."""
RADIAL_FACTOR = (0.1, 3.0)
"""What distortion may do to the radius at the image's corner (distorted / undistorted): a wide lens's barrel
shrinks it to well over a tenth, a pincushion grows it by a few percent."""
_ANGLES = np.linspace(0.0, math.radians(MAX_FOV_DEG / 2), 4001)
"""Ray angles off the axis the radial function is sampled at (0.02 degree apart)."""
_R = np.tan(_ANGLES)


def implausibility(width: int, height: int, fx: float, fy: float, cx: float, cy: float,
                   distortion: tuple[float, ...]) -> str | None:
    """Why these intrinsics (positive, finite numbers) cannot be a camera's, or None when they can."""
    if not (0 <= cx <= width and 0 <= cy <= height):
        return (f"the principal point ({cx:g}, {cy:g}) is outside the {width}x{height} image (a lens's centre is "
                "inside it, usually near the middle)")
    if not 1 / MAX_ASPECT <= fy / fx <= MAX_ASPECT:
        return f"fy / fx = {fy / fx:.3g} is not a camera's (pixels are about square: within 0.5..2)"
    if reason := _field_of_view(math.atan, width, height, fx, fy, cx, cy):
        return reason
    if any(distortion[:2]) or any(distortion[4:8]):
        angle = _radial_angle(distortion, math.hypot(max(cx, width - cx) / fx, max(cy, height - cy) / fy))
        return angle if isinstance(angle, str) else _field_of_view(angle, width, height, fx, fy, cx, cy)
    return None


def _field_of_view(angle: Callable[[float], float], width: int, height: int, fx: float, fy: float, cx: float,
                   cy: float) -> str | None:
    """Why the field of view (each edge's ray angle by ``angle`` of its normalized radius) is not a camera's."""
    hfov = math.degrees(angle(cx / fx) + angle((width - cx) / fx))
    vfov = math.degrees(angle(cy / fy) + angle((height - cy) / fy))
    if not MIN_HFOV_DEG <= hfov <= MAX_FOV_DEG:  # (fy / fx is bounded: the vertical one follows)
        return (f"a field of view of {hfov:.3g} x {vfov:.3g} degrees (fx {fx:g}, fy {fy:g} px for {width}x{height}) "
                f"is not a camera's: {MIN_HFOV_DEG:g}..{MAX_FOV_DEG:g} degrees across")
    return None


def _radial_angle(distortion: tuple[float, ...], corner: float) -> Callable[[float], float] | str:
    """The ray angle of a distorted normalized radius (a function), or why the distortion is not one-to-one out to
    ``corner`` (the normalized radius of the image's farthest corner)."""
    k = np.zeros(8)
    k[:min(8, len(distortion))] = distortion[:8]
    r2 = _R * _R
    numerator = 1 + r2 * (k[0] + r2 * (k[1] + r2 * k[4]))
    denominator = 1 + r2 * (k[5] + r2 * (k[6] + r2 * k[7]))
    with np.errstate(all="ignore"):
        distorted = _R * numerator / denominator
    reached = np.flatnonzero(distorted >= corner)
    end = int(reached[0]) + 1 if len(reached) else len(_R)
    folds = ~((np.diff(distorted[:end]) > 0) & (denominator[1:end] > 0))
    if folds.any():
        at = math.degrees(_ANGLES[int(np.argmax(folds))])
        return (f"the distortion {_coefficients(distortion)} is not one-to-one over the image: its radial function "
                f"turns back {at:.0f} degrees off the axis, so two rays would land on one pixel")
    if not len(reached):
        return (f"the distortion {_coefficients(distortion)} maps the image's corners to no ray within "
                f"{MAX_FOV_DEG / 2:g} degrees of the axis")
    low, high = RADIAL_FACTOR
    if not low <= (factor := corner / _R[end - 1]) <= high:
        return (f"the distortion {_coefficients(distortion)} scales the radius at the image's corner by {factor:.3g} "
                f"(a lens stays within {low:g}..{high:g})")
    angles, radii = _ANGLES[:end], distorted[:end]
    return lambda r: float(np.interp(r, radii, angles))


def _coefficients(distortion: tuple[float, ...]) -> str:
    return "(" + ", ".join(f"{c:.3g}" for c in distortion) + ")"
