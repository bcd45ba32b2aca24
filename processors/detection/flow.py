"""Move boxes between detector keyframes with sparse optical flow (median motion of corners inside)."""

from __future__ import annotations

import cv2
import numpy as np

from uav_values.box import Box


def shift_boxes(prev_gray: np.ndarray, gray: np.ndarray, boxes: list[Box]) -> list[Box | None]:
    """Each box moved by the median Lucas-Kanade motion of the corners found inside it.

    One pyramidal LK call for all boxes. Returns None for a box whose content could not be
    followed (fewer than 4 corners tracked).
    """
    h, w = prev_gray.shape
    pts, owner = [], []
    for i, (x, y, bw, bh) in enumerate(boxes):
        x0, y0 = max(int(x), 0), max(int(y), 0)
        x1, y1 = min(int(x + bw), w), min(int(y + bh), h)
        if x1 - x0 < 8 or y1 - y0 < 8:
            continue
        corners = cv2.goodFeaturesToTrack(prev_gray[y0:y1, x0:x1], 30, 0.01, 4)
        if corners is not None:
            pts.append(corners.reshape(-1, 2) + (x0, y0))
            owner += [i] * len(corners)
    out: list[Box | None] = [None] * len(boxes)
    if not pts:
        return out
    p0 = np.vstack(pts).astype(np.float32).reshape(-1, 1, 2)
    # nextPts None: OpenCV allocates it (the stub types it as a required array)
    p1, status, _ = cv2.calcOpticalFlowPyrLK(prev_gray, gray, p0, None, winSize=(15, 15), maxLevel=2)  # type: ignore[call-overload]
    motion = (p1 - p0).reshape(-1, 2)
    ok = status.reshape(-1) == 1
    owner_arr = np.array(owner)
    for i, box in enumerate(boxes):
        sel = ok & (owner_arr == i)
        if sel.sum() >= 4:
            dx, dy = np.median(motion[sel], axis=0)
            out[i] = (box[0] + float(dx), box[1] + float(dy), box[2], box[3])
    return out
