"""A track's look: a colour histogram of the middle of its box, cheap enough to take on the loop every frame.

The histogram is of hue and saturation (:data:`BINS`), so a change of light (a cloud, a shadow) moves it less than
it moves the pixels; it is taken from the box's middle (:data:`INSET` of each side left out: the processor's overlay
is drawn on the box's edge, and the edge holds the background), on at most :data:`MAX_SIDE_PX` pixels a side (a
larger box is sampled with a stride). Measured on this machine (scripts/bench_lock.py): 10-20 us for a box up to
120 x 60 px, 40 us for 300 x 200; a comparison 1 us.
"""

from __future__ import annotations

import cv2
import numpy as np

from uav_values.box import PixelBox

BINS = (16, 8)
"""Hue and saturation bins."""

INSET = 0.2
"""The share of the box's width (height) left out on the left and right (top and bottom)."""

MAX_SIDE_PX = 64
"""A box's middle is sampled to at most this many pixels a side."""

Look = np.ndarray
"""A histogram of :data:`BINS`, float32, summing to 1."""


def look(image: np.ndarray, box: PixelBox) -> Look | None:
    """The look of ``box`` (x, y, w, h, frame pixels) in the BGR ``image``; None when its middle has no pixels in
    the frame."""
    x, y, w, h = box
    height, width = image.shape[:2]
    x0, x1 = max(0, x + round(w * INSET)), min(width, x + w - round(w * INSET))
    y0, y1 = max(0, y + round(h * INSET)), min(height, y + h - round(h * INSET))
    if x1 <= x0 or y1 <= y0:
        return None
    step = max(1, -(-max(x1 - x0, y1 - y0) // MAX_SIDE_PX))
    middle = np.ascontiguousarray(image[y0:y1:step, x0:x1:step])
    hsv = cv2.cvtColor(middle, cv2.COLOR_BGR2HSV)
    hist: np.ndarray = cv2.calcHist([hsv], [0, 1], None, list(BINS), [0, 180, 0, 256])
    return hist / max(float(hist.sum()), 1.0)


def likeness(a: Look, b: Look) -> float:
    """How alike two looks are: 1 the same colours, 0 none in common (one minus the Bhattacharyya distance)."""
    return 1.0 - float(cv2.compareHist(a, b, cv2.HISTCMP_BHATTACHARYYA))


def blend(kept: Look | None, new: Look | None, weight: float) -> Look | None:
    """``kept`` moved ``weight`` of the way to ``new`` (either alone when the other is None)."""
    if kept is None or new is None:
        return new if kept is None else kept
    return kept * (1.0 - weight) + new * weight
