"""The ground the simulated camera looks at: a large, deterministic, real-looking texture.

Photographed grass and gravel (scikit-image's sample images) are tiled seamlessly, blended by
smooth random masks, tinted, and strewn with paths, stones and bushes, so that every part of the
ground looks different to a feature matcher. The texture repeats every ``period_m`` metres
(about 100 m); a mip pyramid keeps high-altitude views free of aliasing.
"""

from __future__ import annotations

import functools
import importlib.util
import logging
import math
from pathlib import Path

import cv2
import numpy as np

from sources.errors import SourceError

logger = logging.getLogger(__name__)

TEXTURE_PX = 4096
METRES_PER_PX = 0.025
"""Ground resolution of the finest level; a 640-px camera with a 62 degree view sees about 2 cm per pixel at 10 m."""


class GroundTexture:
    """A square BGR texture covering ``period_m`` x ``period_m`` metres, repeated without seams.

    Texture pixel (col, row) of level 0 covers ground (n, e) with col = e / mpp + size / 2 and
    row = -n / mpp + size / 2: north is up in the texture, east to the right.
    """

    def __init__(self, image: np.ndarray, metres_per_px: float) -> None:
        self.levels = [image]
        while self.levels[-1].shape[0] > 256:
            self.levels.append(cv2.pyrDown(self.levels[-1]))
        self.metres_per_px = metres_per_px
        self.size = image.shape[0]
        self.period_m = self.size * metres_per_px

    def level_for(self, ground_sample_m: float) -> int:
        """The coarsest level still at least as fine as ``ground_sample_m`` metres per pixel."""
        ratio = max(ground_sample_m / self.metres_per_px, 1.0)
        return min(int(math.log2(ratio)), len(self.levels) - 1)

    def ground_to_texture(self, level: int) -> np.ndarray:
        """3x3 matrix taking ground ``(n, e, 1)`` to pixel coordinates of ``level``."""
        scale = 1.0 / (self.metres_per_px * 2 ** level)
        half = self.levels[level].shape[0] / 2
        return np.array([[0.0, scale, half], [-scale, 0.0, half], [0.0, 0.0, 1.0]])


@functools.cache
def default_ground(seed: int = 0) -> GroundTexture:
    """The ground texture for ``seed``, generated once per process (about a second)."""
    return GroundTexture(build_mosaic(TEXTURE_PX, seed), METRES_PER_PX)


def build_mosaic(size: int, seed: int) -> np.ndarray:
    """A ``size`` x ``size`` BGR ground mosaic, identical for the same seed and seamless when tiled."""
    grass_photo, gravel_photo = _sample_photo("grass"), _sample_photo("gravel")
    rng = np.random.default_rng(seed)
    grass_a = _tint(_seamless_tiles(grass_photo, size, rng), (0.45, 0.85, 0.55))
    grass_b = _tint(_seamless_tiles(np.rot90(grass_photo), size, rng), (0.4, 0.75, 0.6))
    gravel = _tint(_seamless_tiles(gravel_photo, size, rng), (0.75, 0.8, 0.85))
    soil = _tint(cv2.GaussianBlur(_seamless_tiles(gravel_photo, size, rng), (0, 0), 2), (0.45, 0.6, 0.75))
    grass = _blend(grass_a, grass_b, _smooth_mask(rng, size, cells=16, sharpness=3.0))  # hides the mirror axes
    ground = _blend(gravel, soil, _smooth_mask(rng, size, cells=10, sharpness=4.0))
    mosaic = _blend(ground, grass, _smooth_mask(rng, size, cells=6, sharpness=6.0))
    light = 0.7 + 0.3 * _smooth_mask(rng, size, cells=24, sharpness=1.0)  # patchy light and moisture
    mosaic = cv2.blendLinear(mosaic, np.zeros_like(mosaic), light, 1 - light)
    _scatter_features(mosaic, rng)
    return mosaic


def _sample_photo(name: str) -> np.ndarray:
    """scikit-image's bundled greyscale photograph ``name`` (as ``skimage.data.<name>()`` returns it), read with
    OpenCV: importing ``skimage.data``'s loader (``skimage.io``) would add a second or more to the start."""
    spec = importlib.util.find_spec("skimage")
    if spec is None or spec.origin is None:
        raise SourceError("the simulated camera needs scikit-image for its ground texture: pip install scikit-image")
    path = Path(spec.origin).parent / "data" / f"{name}.png"
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if image is None:
        raise SourceError(f"{path} (scikit-image's sample photograph) is missing: pip install --force-reinstall "
                          "scikit-image")
    return image


def _seamless_tiles(tile: np.ndarray, size: int, rng: np.random.Generator) -> np.ndarray:
    """Mirror-tile a grey sample over the canvas (continuous at every seam), randomly shifted."""
    quad = np.block([[tile, tile[:, ::-1]], [tile[::-1, :], tile[::-1, ::-1]]])
    reps = -(-size // quad.shape[0])
    canvas = np.tile(quad, (reps, reps))[:size, :size]
    shift = rng.integers(0, quad.shape[0], size=2)
    return np.ascontiguousarray(np.roll(canvas, tuple(shift), axis=(0, 1)))


def _tint(grey: np.ndarray, bgr: tuple[float, float, float]) -> np.ndarray:
    return cv2.merge([cv2.convertScaleAbs(grey, alpha=gain) for gain in bgr])


def _blend(under: np.ndarray, over: np.ndarray, weight: np.ndarray) -> np.ndarray:
    return cv2.blendLinear(under, over, 1 - weight, weight)


def _smooth_mask(rng: np.random.Generator, size: int, cells: int, sharpness: float) -> np.ndarray:
    """Periodic smooth noise in [0, 1] (float32, size x size): a random grid upsampled with wrap-around."""
    grid = rng.random((cells, cells)).astype(np.float32)
    padded = np.pad(grid, 2, mode="wrap")
    step = 512 / cells
    medium = cv2.resize(padded, (round(step * (cells + 4)),) * 2, interpolation=cv2.INTER_CUBIC)
    offset = round(2 * step)
    medium = medium[offset:offset + 512, offset:offset + 512]
    medium = 1 / (1 + np.exp(-sharpness * (medium - 0.5)))
    wrapped = np.pad(medium, 1, mode="wrap")
    scale = size / 512
    big = cv2.resize(wrapped, (round(514 * scale),) * 2, interpolation=cv2.INTER_LINEAR)
    return np.ascontiguousarray(big[round(scale):round(scale) + size, round(scale):round(scale) + size])


def _scatter_features(image: np.ndarray, rng: np.random.Generator) -> None:
    """Paths, stones and bushes drawn in place: unique landmarks for trackers and feature matchers."""
    size = image.shape[0]
    for _ in range(5):  # dirt paths: smooth random walks
        heading = np.cumsum(rng.normal(0, 0.25, size=40)) + rng.random() * 2 * np.pi
        steps = np.column_stack([np.cos(heading), np.sin(heading)]) * size / 60
        points = np.cumsum(steps, axis=0) + rng.random(2) * size
        width = int(rng.integers(20, 45))
        cv2.polylines(image, [points.astype(np.int32)], False, (70, 100, 130), width, cv2.LINE_AA)
    for _ in range(900):  # stones and bushes
        centre = tuple(int(c) for c in rng.integers(0, size, size=2))
        axes = tuple(int(a) for a in rng.integers(3, 28, size=2))
        if rng.random() < 0.5:
            colour = tuple(int(c) for c in rng.integers(90, 200) * np.array([1.0, 1.0, 1.05]))
        else:
            colour = (int(rng.integers(10, 50)), int(rng.integers(60, 120)), int(rng.integers(20, 60)))
        angle = float(rng.integers(0, 180))
        cv2.ellipse(image, centre, axes, angle, 0, 360, colour, -1, cv2.LINE_AA)
        cv2.ellipse(image, centre, axes, angle, 0, 360, (20, 25, 30), 1, cv2.LINE_AA)
