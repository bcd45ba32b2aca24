"""Generated video clips for tests that need a file source."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np


def create_video_file(path: Path, *, frames: int = 30, width: int = 160, height: int = 120, fps: float = 15.0,
                      fourcc: str = "mp4v") -> Path:
    """Write a clip whose frame ``i`` shows a white bar at column ``8 * i`` on a textured background."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*fourcc), fps, (width, height))
    assert writer.isOpened(), f"cannot write {path}"
    rng = np.random.default_rng(1)
    background = cv2.resize(rng.integers(0, 200, size=(height // 8, width // 8, 3), dtype=np.uint8),
                            (width, height), interpolation=cv2.INTER_CUBIC)
    for i in range(frames):
        image = background.copy()
        x = (8 * i) % (width - 8)
        image[:, x:x + 8] = 255
        writer.write(image)
    writer.release()
    return path
