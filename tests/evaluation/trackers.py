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


class Failing:
    """Tracks nothing; raises ValueError on frame ``frame`` (1 = the first) of the sequence whose first box starts
    at x = ``first_x``, sleeps while the file ``hold`` exists there instead, and notes each start in ``log``."""

    def __init__(self, frame: int = 5, first_x: int = 10, hold: str = "", log: str = "") -> None:
        self.tmMgr = None
        self.box = None
        self.frame, self.first_x, self.hold, self.log = frame, first_x, hold, log
        self.chosen = False

    def catch_cmd(self, roi):
        self.chosen = roi[0] == self.first_x
        if self.log:
            with open(self.log, "a") as log:
                log.write(f"{roi[0]}\n")

    def photo_processing(self, frame):
        if not self.chosen or self.tmMgr.snapshot().frame_seq != self.frame:
            return
        if not self.hold:
            raise ValueError(f"bad reshape on frame {self.frame}")
        import os
        import time
        while os.path.exists(self.hold):
            time.sleep(0.05)


class ReportsBox:
    """Reports the same ``box`` on every frame, whatever it is."""

    def __init__(self, box: list) -> None:
        self.tmMgr = None
        self.box = tuple(box)

    def catch_cmd(self, roi):
        pass

    def photo_processing(self, frame):
        pass


class ThreadsProbe:
    """Saves every frame with the OpenCV threads it runs on and its place in the sequence (never tracks)."""

    def __init__(self) -> None:
        self.tmMgr = None
        self.box = None

    def catch_cmd(self, roi):
        pass

    def photo_processing(self, frame):
        import cv2

        seen = self.tmMgr.snapshot()
        self.tmMgr.save(frame, threads=cv2.getNumThreads(), seq=seen.frame_seq, t_s=seen.frame_t_s,
                        alt=seen.rel_alt_m)
