"""Whether a set of board views can constrain a calibration: tilted boards, in more than one direction, spread
over the image.

A board only moved, never tilted, fits any focal length as well as the true one (a board twice as far away with a
lens twice as long gives the same picture): OpenCV still returns a solution, with a tiny RMS and a focal length of
thousands of pixels. Tilt is measured from each view alone, without any intrinsics: a board square to the camera
maps to the image by an affine map, a tilted one by a perspective whose scale changes across the board (the
near edge looks larger than the far one). Zhang's method needs at least two views tilted about different axes;
the lens's distortion is constrained only where the board has been.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from sources.calibration_boards import View

MIN_FORESHORTENING = 0.03
"""A view counts as tilted when the image's scale changes by 3 % across the board (a board 0.25 m wide 0.5 m away
tilted by about 5 degrees; the views the manual asks for, tilted up to 45 degrees, change it by 10-50 %)."""
MIN_TILTED_VIEWS = 3
MIN_AXES_APART_DEG = 20.0
"""The tilted views' directions (the way the scale grows, mod 180 degrees) must differ by this much somewhere."""
GRID = 4
MIN_CELLS = 8
"""The views' corners must reach at least 8 of the image's 4 x 4 cells (half the image)."""


def coverage_problem(views: list[View], size: tuple[int, int]) -> str | None:
    """What the views fail to show for a calibration (with what to do), or None when they are enough."""
    directions = [d for d in (_tilt_direction(view) for view in views) if d is not None]
    tilt = ("tilt it towards and away from the camera, up to about 45 degrees, left-right in some views and up-down "
            "in others, then calibrate again")
    if len(directions) < MIN_TILTED_VIEWS:
        return (f"the board was not tilted in enough views ({len(directions)} of {len(views)} tilted, "
                f"{MIN_TILTED_VIEWS} needed): a board only moved square to the camera cannot tell the focal length; "
                + tilt)
    spread = max(abs(math.sin(math.radians(a - b))) for a in directions for b in directions)
    if spread < math.sin(math.radians(MIN_AXES_APART_DEG)):
        return (f"the board was always tilted the same way (its tilts are within {MIN_AXES_APART_DEG:g} degrees): "
                + tilt)
    width, height = size
    points = np.concatenate([points.reshape(-1, 2) for _, points in views])
    columns = np.clip((points[:, 0] * GRID / width).astype(int), 0, GRID - 1)
    rows = np.clip((points[:, 1] * GRID / height).astype(int), 0, GRID - 1)
    cells = len(set(zip(columns.tolist(), rows.tolist(), strict=True)))
    if cells < MIN_CELLS:
        return (f"the board covered only {cells} of the image's {GRID * GRID} cells ({GRID}x{GRID}), "
                f"{MIN_CELLS} needed: the lens's distortion is unknown where the board has not been; show it near the "
                "corners and edges of the image too, then calibrate again")
    return None


def _tilt_direction(view: View) -> float | None:
    """The direction (degrees, mod 180, on the board) in which the image's scale grows, or None when the view is
    square to the camera (its scale changes less than MIN_FORESHORTENING across the board)."""
    objects, points = view
    board = objects.reshape(-1, 3)[:, :2].astype(np.float64)
    homography, _ = cv2.findHomography(board, points.reshape(-1, 2).astype(np.float64))
    if homography is None or not np.all(np.isfinite(homography)) or homography[2, 2] == 0:
        return None
    perspective = homography[2] / homography[2, 2]
    scale = board @ perspective[:2] + 1.0  # the homogeneous w: the image scale goes as 1/w
    if np.any(scale <= 0):
        return None
    if scale.max() / scale.min() - 1.0 < MIN_FORESHORTENING:
        return None
    return math.degrees(math.atan2(perspective[1], perspective[0])) % 180.0
