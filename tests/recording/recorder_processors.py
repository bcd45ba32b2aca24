"""Processors used by the recorder tests (loaded by spec: ``tests.recording.recorder_processors:Class``)."""

import math
import time

import numpy as np


class SaveEveryFifth:
    """Saves every 5th frame with a counter, a label and a small list, then draws on the frame."""

    def __init__(self):
        self.tmMgr = None
        self.count = 0

    def photo_processing(self, frame):
        self.count += 1
        if self.count % 5 == 0:
            self.tmMgr.save(frame, n=self.count, label=f"f{self.count}", box=[1, 2, 3, 4],
                            mean=np.float32(frame[::8, ::8].mean()))
            frame[:40, :40] = 255  # drawn after saving: must not reach the saved image


class SaveEveryFrame:
    """Saves every frame (the recording benchmark and the pressure test)."""

    def __init__(self):
        self.tmMgr = None
        self.count = 0

    def photo_processing(self, frame):
        self.count += 1
        self.tmMgr.save(frame, n=self.count)


class SavesInCatchCmd:
    """Calls tmMgr.save from catch_cmd, where there is no frame being processed."""

    def __init__(self):
        self.tmMgr = None
        self.frame = None

    def photo_processing(self, frame):
        self.frame = frame

    def catch_cmd(self, roi):
        self.tmMgr.save(self.frame, roi=list(roi))


class BoxOnEvenFrames:
    """Reports a box (x = frame count) on even frames and none on odd ones."""

    def __init__(self):
        self.tmMgr = None
        self.count = 0
        self.box = None

    def photo_processing(self, frame):
        self.count += 1
        self.box = (self.count, 2 * self.count, 10.4, 20) if self.count % 2 == 0 else None


class FrameClock:
    """Saves every frame with what ``tmMgr.snapshot()`` says of it: its number and capture time."""

    def __init__(self):
        self.tmMgr = None

    def photo_processing(self, frame):
        seen = self.tmMgr.snapshot()
        self.tmMgr.save(frame, clock_seq=seen.frame_seq, clock_t_ns=seen.frame_t_ns, clock_wall_ns=seen.frame_t_wall_ns)


class RedCar:
    """Reports the box of the largest red blob: the sim: camera's car (a detector that cannot lose it)."""

    def __init__(self):
        self.tmMgr = None
        self.box = None

    def photo_processing(self, frame):
        blobs = self.red_blobs(frame)
        if not blobs:
            self.box = None
            return
        self.box = max(blobs, key=lambda blob: blob[4])[:4]

    @staticmethod
    def red_blobs(frame):
        """(x, y, w, h, area) of each red blob (the sim: camera's cars) of at least 30 pixels."""
        import cv2

        b, g, r = frame[..., 0].astype(np.int16), frame[..., 1].astype(np.int16), frame[..., 2].astype(np.int16)
        mask = ((r - np.maximum(b, g)) > 90).astype(np.uint8)
        mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, np.ones((5, 5), np.uint8))  # across the roof's white lines
        count, _, stats, _ = cv2.connectedComponentsWithStats(mask)
        return [tuple(int(v) for v in stats[i]) for i in range(1, count) if stats[i, cv2.CC_STAT_AREA] >= 30]


class RedCars(RedCar):
    """RedCar that also reports every red blob as a detection ``car``, its score the blob's share of the red pixels.

    F1 makes its detections malformed (a NaN score), F2 makes them right again.
    """

    def __init__(self):
        super().__init__()
        self.detections = None
        self.broken = False

    def photo_processing(self, frame):
        super().photo_processing(frame)
        blobs = self.red_blobs(frame)
        total = sum(blob[4] for blob in blobs) or 1
        self.detections = [(blob[:4], "car", math.nan if self.broken else blob[4] / total) for blob in blobs]

    def customize_processing(self, id):
        self.broken = id == 1


class Slow:
    """A processor slower than the recorder holds a frame's row (250 ms a frame: a detector on a Pi)."""

    def __init__(self):
        self.tmMgr = None

    def photo_processing(self, frame):
        time.sleep(0.25)


class FixedBox:
    """Reports the same box and one detection on every frame (geo-located by the recorder from the telemetry)."""

    box = (60, 40, 40, 40)

    def __init__(self):
        self.tmMgr = None
        self.detections = [((10, 10, 30, 20), "thing", 0.9)]

    def photo_processing(self, frame):
        pass
