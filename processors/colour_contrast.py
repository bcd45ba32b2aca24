"""Whether a box's colours look like its surroundings rather than like the target: a loss cue that needs no shape.

A covered target (a car under trees, a boat behind a pier, a box painted over with the background beside it)
leaves a tracker's box on background, and a Siamese tracker is often sure of a peak there. Its colours then
match the ring around the box and no longer the target's. :func:`background_likeness` is that difference, from
hue x saturation histograms compared by Bhattacharyya similarity (brightness is left out: a shadow or a change
of exposure does not change it).
"""

from __future__ import annotations

import cv2
import numpy as np

from uav_values.box import Box

BINS = (16, 4)
"""Hue and saturation bins of the histograms."""


def histogram(image: np.ndarray) -> np.ndarray:
    """Hue x saturation histogram of a BGR patch, summing to 1."""
    hsv = cv2.cvtColor(image, cv2.COLOR_BGR2HSV)
    counts = cv2.calcHist([hsv], [0, 1], None, list(BINS), [0, 180, 0, 256])
    return counts / max(float(counts.sum()), 1.0)


def similarity(a: np.ndarray, b: np.ndarray) -> float:
    """1 - Bhattacharyya distance of two histograms: 1 alike, 0 nothing in common."""
    return 1.0 - float(cv2.compareHist(a, b, cv2.HISTCMP_BHATTACHARYYA))


def box_histogram(image: np.ndarray, box: Box) -> np.ndarray | None:
    """:func:`histogram` of the part of ``box`` inside the frame; None when that is under 2 px a side."""
    x, y, w, h = (int(round(v)) for v in box)
    x0, y0, x1, y1 = max(x, 0), max(y, 0), min(x + w, image.shape[1]), min(y + h, image.shape[0])
    return histogram(image[y0:y1, x0:x1]) if x1 - x0 >= 2 and y1 - y0 >= 2 else None


def box_and_ring(image: np.ndarray, box: Box) -> tuple[np.ndarray, np.ndarray] | None:
    """Histograms of ``box`` and of the ring around it (the box grown by half its size a side, less the box), in
    the frame; None as :func:`box_histogram`, or when the ring is empty."""
    inner = box_histogram(image, box)
    if inner is None:
        return None
    x, y, w, h = (int(round(v)) for v in box)
    height, width = image.shape[:2]
    inside = (min(x + w, width) - max(x, 0)) * (min(y + h, height) - max(y, 0))
    gx0, gy0 = max(x - w // 2, 0), max(y - h // 2, 0)
    gx1, gy1 = min(x + w + w // 2, width), min(y + h + h // 2, height)
    ring = np.clip(histogram(image[gy0:gy1, gx0:gx1]) * ((gx1 - gx0) * (gy1 - gy0)) - inner * inside, 0.0, None)
    total = float(ring.sum())
    return (inner, ring / total) if total > 0 else None


def background_likeness(image: np.ndarray, box: Box, target: np.ndarray) -> float | None:
    """How much more the colours under ``box`` are like the ring around it than like ``target`` (a
    :func:`histogram` of the selection): -1..1, higher when the box shows background; None as
    :func:`box_and_ring`."""
    found = box_and_ring(image, box)
    if found is None:
        return None
    inner, ring = found
    return similarity(inner, ring) - similarity(inner, target)
