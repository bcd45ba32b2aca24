"""``synthetic:`` — a generated scene: a textured target moving over a textured background.

Deterministic for a given seed, so the demo and the tests need no video files.
"""

from __future__ import annotations

import math
from typing import Any

import cv2
import numpy as np

from sources.base import CaptureSource
from sources.pacing import Pacer
from sources.uri import SourceUri


def _texture(rng: np.random.Generator, height: int, width: int, cell: int) -> np.ndarray:
    """Smooth coloured noise plus fine grain: enough structure for trackers and feature matchers."""
    coarse = rng.integers(0, 256, size=(max(2, height // cell), max(2, width // cell), 3), dtype=np.uint8)
    smooth = cv2.resize(coarse, (width, height), interpolation=cv2.INTER_CUBIC)
    grain = rng.integers(-40, 41, size=(height, width, 1), dtype=np.int16)
    texture: np.ndarray = np.clip(smooth.astype(np.int16) + grain, 0, 255).astype(np.uint8)
    return texture


class SyntheticScene:
    """Renders frame ``i`` of the scene and knows where the target is in it.

    The target (a patterned square, a tenth of the frame wide) follows a Lissajous path that
    repeats every ``period_frames``.
    """

    def __init__(self, width: int = 640, height: int = 480, seed: int = 0, period_frames: int = 300) -> None:
        rng = np.random.default_rng(seed)
        self.width, self.height, self.period = width, height, period_frames
        self.background = _texture(rng, height, width, cell=16)
        side = max(8, width // 10)
        target = _texture(rng, side, side, cell=4)
        target[::max(2, side // 4), :] = (0, 0, 255)
        target[:, ::max(2, side // 4)] = (255, 255, 0)
        self.target = target

    def target_box(self, i: int) -> tuple[int, int, int, int]:
        """(x, y, w, h) of the target in frame ``i``."""
        side = self.target.shape[0]
        phase = 2 * math.pi * i / self.period
        cx = self.width / 2 + 0.35 * self.width * math.sin(phase)
        cy = self.height / 2 + 0.3 * self.height * math.sin(2 * phase + 0.5)
        return int(cx - side / 2), int(cy - side / 2), side, side

    def render(self, i: int) -> np.ndarray:
        """A new BGR frame (the caller owns it)."""
        image = self.background.copy()
        x, y, w, h = self.target_box(i)
        image[y:y + h, x:x + w] = self.target
        return image


class SyntheticSource(CaptureSource):
    """URI: ``synthetic:[?width=640&height=480&fps=30&seed=0&realtime=1]``."""

    kind = "synthetic"

    def __init__(self, uri: str = "synthetic:", *, width: int = 640, height: int = 480, fps: float = 30.0,
                 seed: int = 0, realtime: bool = True) -> None:
        super().__init__(uri, f"seed={seed}")
        self.scene = SyntheticScene(width, height, seed)
        self.width, self.height, self.fps = width, height, fps
        self.realtime = realtime
        self._index = 0
        self._pacer: Pacer | None = None

    @classmethod
    def from_uri(cls, uri: SourceUri, **_context: Any) -> SyntheticSource:
        source = cls(uri.text, width=uri.take_int("width", 640) or 640, height=uri.take_int("height", 480) or 480,
                     fps=uri.take_float("fps", 30.0) or 30.0, seed=uri.take_int("seed", 0) or 0,
                     realtime=uri.take_bool("realtime", True))
        uri.finish()
        return source

    def _open_device(self) -> None:
        self._pacer = Pacer(self.fps if self.realtime else 0, self._stop)

    def _grab(self) -> np.ndarray | None:
        assert self._pacer is not None
        if not self._pacer.wait():
            return None
        image = self.scene.render(self._index)
        self._index += 1
        return image

    def _extra_properties(self) -> dict[str, Any]:
        return {"realtime": self.realtime}
