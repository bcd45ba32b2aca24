"""Appearance of a target as a small grayscale template: how well it matches now, and where it is near a point.

Normalised cross-correlation (``cv2.matchTemplate``, TM_CCOEFF_NORMED) needs no keypoints, so it works on
weakly textured targets (a person seen from above, a boat, a bird) where SIFT finds next to nothing. Every
call works on a window around the target resampled so that the target is at most :data:`MAX_SIDE` pixels:
its cost is bounded whatever the frame or target size.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from uav_values.box import Box

MAX_SIDE = 32
"""The target's longer side is resampled to at most this many pixels for matching."""


@dataclass(frozen=True)
class Found:
    box: Box
    score: float
    """Normalised cross-correlation of the template at ``box``, -1..1."""


def template(gray: np.ndarray, box: Box) -> np.ndarray | None:
    """The target's appearance: the grayscale patch under ``box``, longer side :data:`MAX_SIDE`, float32."""
    x, y, w, h = (int(round(v)) for v in box)
    x0, y0, x1, y1 = max(x, 0), max(y, 0), min(x + w, gray.shape[1]), min(y + h, gray.shape[0])
    if x1 - x0 < 4 or y1 - y0 < 4:
        return None
    k = MAX_SIDE / max(w, h)
    size = (max(4, round(w * k)), max(4, round(h * k)))
    return cv2.resize(gray[y0:y1, x0:x1], size, interpolation=cv2.INTER_AREA).astype(np.float32)


def blend(old: np.ndarray, new: np.ndarray, rate: float) -> np.ndarray:
    """``old`` moved towards ``new`` (resized to it) by ``rate``: a slowly adapting appearance."""
    if new.shape != old.shape:
        new = cv2.resize(new, (old.shape[1], old.shape[0]), interpolation=cv2.INTER_AREA)
    return ((1.0 - rate) * old + rate * new).astype(np.float32)


def adapted(old: np.ndarray, image: np.ndarray, box: Box, rate: float) -> np.ndarray:
    """``old`` blended (:func:`blend`) towards the appearance under ``box`` in the BGR ``image`` (only the box and a
    2-px margin are converted); ``old`` itself when the box is too small or off the image."""
    x, y, w, h = box
    x0, y0 = max(int(x - 2), 0), max(int(y - 2), 0)
    x1, y1 = min(int(x + w + 2) + 1, image.shape[1]), min(int(y + h + 2) + 1, image.shape[0])
    if x1 <= x0 or y1 <= y0:
        return old
    current = template(cv2.cvtColor(image[y0:y1, x0:x1], cv2.COLOR_BGR2GRAY), (x - x0, y - y0, w, h))
    return old if current is None else blend(old, current, rate)


def search(gray: np.ndarray, templates: list[np.ndarray], box: Box, radius: float,
           scales: tuple[float, ...] = (1.0,), max_side: int = MAX_SIDE) -> Found | None:
    """Best match of any template around ``box``: shifted up to ``radius`` x its size, at each scale.

    Args:
        gray: the image (grayscale uint8).
        templates: appearances from :func:`template` (the best of them counts).
        box: where the target was; its size times each scale is the size searched for.
        radius: how far the centre may move, in units of the box's longer side.
        scales: box sizes tried, relative to ``box``.
        max_side: the target's longer side is resampled to at most this (smaller: coarser and cheaper).

    Returns:
        The best box and its score, or None when the window is off the image.
    """
    x, y, w, h = box
    cx, cy = x + w / 2, y + h / 2
    best: Found | None = None
    for scale in scales:
        sw, sh = w * scale, h * scale
        k = min(1.0, max_side / max(sw, sh))  # resample: the target at most max_side px
        reach = radius * max(sw, sh)
        x0, y0 = max(int(cx - sw / 2 - reach), 0), max(int(cy - sh / 2 - reach), 0)
        x1, y1 = min(int(np.ceil(cx + sw / 2 + reach)), gray.shape[1]), min(int(np.ceil(cy + sh / 2 + reach)),
                                                                          gray.shape[0])
        tw, th = max(4, round(sw * k)), max(4, round(sh * k))
        ww, wh = round((x1 - x0) * k), round((y1 - y0) * k)
        if ww < tw or wh < th:
            continue
        window = cv2.resize(gray[y0:y1, x0:x1], (ww, wh), interpolation=cv2.INTER_AREA).astype(np.float32)
        for appearance in templates:
            patch = cv2.resize(appearance, (tw, th), interpolation=cv2.INTER_AREA)
            response = cv2.matchTemplate(window, patch, cv2.TM_CCOEFF_NORMED)
            _, score, _, (px, py) = cv2.minMaxLoc(response)
            if best is None or score > best.score:
                best = Found((x0 + px / k, y0 + py / k, tw / k, th / k), float(score))
    return best
