"""Generated image sequences with known ground truth, for testing and benchmarking processors.

Textures come from scikit-image's bundled photographs (``skimage.data``, offline; a dev dependency),
imported only when a scene is built. Nothing is downloaded.

* :func:`tracking_sequence` - a textured target moving over a textured background along a known
  trajectory, with a partial and a full occlusion by a brick-textured occluder.
* :func:`detection_sequence` - the astronaut photograph (a person) moving over ground, with the
  person's true box per frame (from a hand-drawn box on the photograph).
* :func:`iou` scores a tracked box against the truth.
* :func:`ground_view` - a nadir camera's view of a flat ground texture at a known position, yaw and
  zoom, and :func:`spot_offset_m` the true body-frame offset of a reference spot (position hold).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from uav_values.box import Box


def _tint(gray: np.ndarray, bgr: tuple[float, float, float]) -> np.ndarray:
    return np.clip(gray[..., None].astype(np.float32) * np.array(bgr, np.float32), 0, 255).astype(np.uint8)


def ground_texture(size: int = 1024) -> np.ndarray:
    """A BGR mosaic of ground photographs (grass, gravel, brick), ``size`` x ``size``."""
    from skimage import data

    half = size // 2
    tiles = [
        _tint(data.grass(), (0.6, 1.0, 0.7)),
        _tint(data.gravel(), (0.9, 0.95, 1.0)),
        _tint(data.brick(), (0.7, 0.8, 1.0)),
        _tint(np.ascontiguousarray(data.gravel()[::-1, ::-1]), (1.0, 0.9, 0.8)),
    ]
    tiles = [cv2.resize(t, (half, half), interpolation=cv2.INTER_AREA) for t in tiles]
    return np.vstack([np.hstack(tiles[:2]), np.hstack(tiles[2:])])


@dataclass
class TrackingSequence:
    """Frames with the true target box per frame (None while fully occluded)."""

    frames: list[np.ndarray]
    boxes: list[Box | None]
    partial: range
    """Frames in which part of the target is hidden."""
    full: range
    """Frames in which the whole target is hidden."""
    size: tuple[int, int] = field(default=(320, 240))


def tracking_sequence(size: tuple[int, int] = (320, 240), n_frames: int = 80) -> TrackingSequence:
    """A textured target (a crop of ``astronaut()``) moving on a Lissajous path over ground.

    Frames ~22-32 % of the way in: an occluder covers the target's left 40 %; ~55-65 %: an occluder
    covers it entirely, then moves off. All sizes scale with ``size``; the sequence is deterministic.
    """
    from skimage import data

    w, h = size
    k = w / 320.0
    bg = cv2.resize(ground_texture(1024), (int(w * 1.6), int(h * 1.6)), interpolation=cv2.INTER_AREA)
    tw, th = int(44 * k), int(52 * k)
    astro = cv2.cvtColor(data.astronaut(), cv2.COLOR_RGB2BGR)
    target = cv2.resize(astro[40:280, 150:350], (tw, th), interpolation=cv2.INTER_AREA)
    occ_src = _tint(data.brick(), (0.5, 0.6, 0.9))
    partial = range(int(0.22 * n_frames), int(0.32 * n_frames))
    full = range(int(0.55 * n_frames), int(0.65 * n_frames))
    frames: list[np.ndarray] = []
    boxes: list[Box | None] = []
    for i in range(n_frames):
        s = i / n_frames
        # slow camera drift over the background plus a Lissajous target path
        ox, oy = int(0.25 * w * s), int(0.15 * h * s)
        frame = bg[oy : oy + h, ox : ox + w].copy()
        cx = w / 2 + 0.3 * w * math.sin(2 * math.pi * s)
        cy = h / 2 + 0.25 * h * math.sin(4 * math.pi * s + 0.5)
        x, y = int(round(cx - tw / 2)), int(round(cy - th / 2))
        frame[y : y + th, x : x + tw] = target
        box: Box | None = (float(x), float(y), float(tw), float(th))
        if i in partial:
            ow = int(0.4 * tw)
            frame[y - 6 : y + th + 6, x - 6 : x + ow] = occ_src[: th + 12, : ow + 6]
        elif i in full:
            ow, oh = int(tw * 1.5), int(th * 1.4)
            ox0, oy0 = int(cx - ow / 2), int(cy - oh / 2)
            frame[oy0 : oy0 + oh, ox0 : ox0 + ow] = occ_src[:oh, :ow]
            box = None
        frames.append(frame)
        boxes.append(box)
    return TrackingSequence(frames, boxes, partial, full, (w, h))


ASTRONAUT_PERSON: Box = (20.0, 15.0, 340.0, 497.0)
"""Hand-drawn box of the person in ``skimage.data.astronaut()`` (512 x 512)."""

CHELSEA_CAT: Box = (0.0, 0.0, 420.0, 300.0)
"""Hand-drawn box of the cat in ``skimage.data.chelsea()`` (451 x 300)."""


def detection_sequence(size: tuple[int, int] = (640, 480), n_frames: int = 40) -> tuple[list[np.ndarray], list[Box]]:
    """The astronaut photograph, scaled to 60 % of the frame height, sliding over ground.

    Returns:
        (frames, true person box per frame).
    """
    from skimage import data

    w, h = size
    side = int(0.6 * h)
    k = side / 512.0
    photo = cv2.resize(cv2.cvtColor(data.astronaut(), cv2.COLOR_RGB2BGR), (side, side), interpolation=cv2.INTER_AREA)
    bg = cv2.resize(ground_texture(1024), (w, h), interpolation=cv2.INTER_AREA)
    frames, boxes = [], []
    for i in range(n_frames):
        s = i / max(n_frames - 1, 1)
        x = int(0.05 * w + s * (w - side - 0.1 * w))
        y = int(0.2 * h + 0.15 * h * math.sin(2 * math.pi * s))
        frame = bg.copy()
        frame[y : y + side, x : x + side] = photo
        px, py, pw, ph = ASTRONAUT_PERSON
        frames.append(frame)
        boxes.append((x + px * k, y + py * k, pw * k, min(ph * k, side - py * k)))
    return frames, boxes


def ground_view(
    ground: np.ndarray,
    centre: tuple[float, float],
    yaw_deg: float = 0.0,
    zoom: float = 1.0,
    size: tuple[int, int] = (640, 480),
) -> np.ndarray:
    """Render a nadir view of ``ground`` centred on texel ``centre``.

    View pixel ``p`` shows texel ``centre + R(yaw) @ (p - view_centre) / zoom``; zoom > 1 means lower
    altitude (altitude_now = altitude_at_zoom_1 / zoom).
    """
    w, h = size
    a = math.radians(yaw_deg)
    r = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]]) / zoom
    t = np.array(centre) - r @ np.array([w / 2.0, h / 2.0])
    m = np.hstack([r, t[:, None]])
    return cv2.warpAffine(
        ground, m, (w, h), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderMode=cv2.BORDER_REFLECT
    )


def spot_offset_m(
    spot: tuple[float, float], centre: tuple[float, float], yaw_deg: float, m_per_texel: float
) -> tuple[float, float]:
    """True (forward, right) offset in metres from the vehicle to the ground ``spot``.

    ``centre`` and ``yaw_deg`` are the vehicle's view (as in :func:`ground_view`); image up is forward.
    """
    a = math.radians(yaw_deg)
    rt = np.array([[math.cos(a), math.sin(a)], [-math.sin(a), math.cos(a)]])
    d = rt @ (np.array(spot) - np.array(centre))
    return float(-d[1] * m_per_texel), float(d[0] * m_per_texel)


def iou(a: Box | None, b: Box | None) -> float:
    """Intersection over union of two (x, y, w, h) boxes; 0 when either is None."""
    if a is None or b is None:
        return 0.0
    x0, y0 = max(a[0], b[0]), max(a[1], b[1])
    x1, y1 = min(a[0] + a[2], b[0] + b[2]), min(a[1] + a[3], b[1] + b[3])
    inter = max(0.0, x1 - x0) * max(0.0, y1 - y0)
    return inter / (a[2] * a[3] + b[2] * b[3] - inter)
