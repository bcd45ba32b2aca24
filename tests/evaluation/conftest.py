"""Tiny annotated sequences written into tmp_path, in both layouts."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

SIZE = (96, 64)
"""Frame width, height."""

BOXES = np.array([[10, 12, 20, 16], [14, 12, 20, 16], [np.nan] * 4, [22, 14, 20, 16], [26, 16, 20, 16],
                  [30, 18, 20, 16]])
"""A target moving right; frame 2 has no gt (hidden)."""


def frames() -> list[np.ndarray]:
    images = []
    for box in BOXES:
        image = np.full((SIZE[1], SIZE[0], 3), 40, np.uint8)
        if not np.isnan(box[0]):
            x, y, w, h = (int(v) for v in box)
            image[y:y + h, x:x + w] = (30, 200, 240)
            image[y + 4:y + 8, x + 4:x + 10] = 0
        images.append(image)
    return images


def write_gt(path: Path, boxes: np.ndarray) -> Path:
    path.write_text("".join(",".join("NaN" if np.isnan(v) else f"{v:g}" for v in row) + "\n" for row in boxes))
    return path


def write_video_sequence(folder: Path, boxes: np.ndarray = BOXES) -> Path:
    folder.mkdir(parents=True)
    writer = cv2.VideoWriter(str(folder / "video.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), 10, SIZE)
    for image in frames():
        writer.write(image)
    writer.release()
    write_gt(folder / "gt.txt", boxes)
    return folder


def write_image_sequence(folder: Path, gt_beside: bool = False) -> Path:
    (folder / "img").mkdir(parents=True)
    for index, image in enumerate(frames(), start=1):
        cv2.imwrite(str(folder / "img" / f"{index:04d}.jpg"), image)
    gt = folder.parent / f"{folder.name}.txt" if gt_beside else folder / "groundtruth_rect.txt"
    text = "".join("\t".join("NaN" if np.isnan(v) else f"{v:g}" for v in row) + "\n" for row in BOXES)
    gt.write_text(text)  # OTB files use tabs as often as commas
    return folder


@pytest.fixture
def video_sequence(tmp_path: Path) -> Path:
    return write_video_sequence(tmp_path / "data" / "moving-box")
