"""Video for tests that need a file source: generated clips, and the real-video set (skipped where it is not here)."""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np
import pytest

from processors.detection import DATA_DIR_ENV, find_data_dir

WANT_OF_DATA = "the real-video set"
"""How every skip for want of the aerial-tracking set begins (tests/conftest.py counts them at the end of a run)."""
HOW_TO_GET_IT = (f"set {DATA_DIR_ENV} to the folder holding aerial-tracking/, or build it with "
                 "scripts/build_tracking_set.py (docs/evaluation.md#the-real-video-set)")


def aerial_set(sequence: str = "") -> Path:
    """The aerial-tracking set (``$UAV_TUI_DATA_DIR/aerial-tracking``, else ``shared/data/aerial-tracking`` beside
    the repository), or its ``sequence`` folder; the test is skipped, saying how to get it, where it is not here."""
    try:
        folder = find_data_dir() / "aerial-tracking"
    except FileNotFoundError as exc:  # a wrong UAV_TUI_DATA_DIR is named; the folders searched are not
        wrong = f" ({exc})" if os.environ.get(DATA_DIR_ENV) else ""
        pytest.skip(f"{WANT_OF_DATA} is not here{wrong}: {HOW_TO_GET_IT}")
    if not folder.is_dir():
        pytest.skip(f"{WANT_OF_DATA} is not in {folder.parent}: {HOW_TO_GET_IT}")
    if sequence and not (folder / sequence).is_dir():
        pytest.skip(f"{WANT_OF_DATA} has no {sequence} in {folder}: {HOW_TO_GET_IT}")
    return folder / sequence


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
    return damaged_copy(aerial_set("dtb70-Gull2") / "video.mp4", folder / "damaged.mp4")
