"""Generated video clips for tests that need a file source."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from processors.detection import find_data_dir


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


def damaged_copy(video: Path, path: Path, *, spots: int = 40) -> Path:
    """``video`` with 8 bytes inverted at ``spots`` places across its middle half, as a flaky SD card or a
    lossy stream leaves it: it opens and every frame decodes, and FFmpeg complains of each damaged one."""
    data = bytearray(video.read_bytes())
    size = len(data)
    for spot in range(spots):
        at = size // 4 + spot * (size // 2) // spots
        data[at:at + 8] = bytes(byte ^ 0xFF for byte in data[at:at + 8])
    path.write_bytes(data)
    return path


def damaged_aerial_video(folder: Path) -> Path:
    """A real drone video (the aerial-tracking set's dtb70-Gull2, 1280x720 MPEG-4, 237 frames) damaged by
    :func:`damaged_copy`, in ``folder``; the test is skipped where the set is not here."""
    try:
        video = find_data_dir() / "aerial-tracking" / "dtb70-Gull2" / "video.mp4"
    except FileNotFoundError as exc:
        pytest.skip(str(exc))
    if not video.is_file():
        pytest.skip(f"{video} is not here")
    return damaged_copy(video, folder / "damaged.mp4")
