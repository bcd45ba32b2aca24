"""Processors with known answers, loaded by eval as ``tests/evaluation/trackers.py:Class``."""

from __future__ import annotations

import numpy as np


class ReplaysBoxes:
    """Reports the boxes of a gt-format file, one per frame (NaN rows: no box), shifted by ``dx`` pixels."""

    def __init__(self, boxes: str, dx: float = 0.0) -> None:
        self.tmMgr = None
        self.boxes = np.loadtxt(boxes, delimiter=",", ndmin=2)
        self.dx = dx
        self.frame = -1
        self.box = None
        self.roi = None

    def catch_cmd(self, roi):
        self.roi = roi

    def photo_processing(self, frame):
        self.frame += 1
        x, y, w, h = self.boxes[self.frame]
        self.box = None if np.isnan(x) else (x + self.dx, y, w, h)


class NeverFinds:
    """Has catch_cmd but never reports a box (always lost)."""

    def __init__(self) -> None:
        self.tmMgr = None
        self.box = None

    def catch_cmd(self, roi):
        pass

    def photo_processing(self, frame):
        pass


class NoCatchCmd:
    def __init__(self) -> None:
        self.tmMgr = None

    def photo_processing(self, frame):
        pass
