"""Processors for the replay tests (loaded by spec: ``tests.replay.replay_processors:Class``)."""

import time

import numpy as np


class Brightness:
    """Steers by the frame's brightness (F2 reverses it), reports a box, stores what tmMgr.snapshot() said,
    draws an overlay."""

    sign = 1.0

    def __init__(self):
        self.tmMgr = None
        self.box = None
        self.vector = None
        self.gain = 1.0

    def customize_processing(self, id):
        self.gain = -1.0 if id == 2 else 1.0

    def photo_processing(self, frame):
        level = float(frame[::4, ::4].mean())
        self.vector = (self.sign * self.gain * (level - 110.0) / 40.0, 0.2, 1.0)
        rows = np.flatnonzero(frame[::4, ::4, 2].mean(axis=1) > level)
        self.box = (8, int(rows[0]) * 4, 32, 32) if len(rows) else None
        seen = self.tmMgr.snapshot()
        self.tmMgr.save(frame, seen_t_mono_ns=seen.t_mono_ns, seen_north_m=seen.north_m, seen_mode=seen.flight_mode,
                        gain=self.gain)
        frame[:16, :16] = 255  # the overlay: never in the recorded video

    def getPreparedVector(self):
        return self.vector


class Darkness(Brightness):
    """The same with the opposite sign: another processor to compare with."""

    sign = -1.0


class Idle:
    """Looks at nothing, saves nothing: the recording tests count only the video's items."""

    def __init__(self):
        self.tmMgr = None

    def photo_processing(self, frame):
        pass


class SlowBrightness(Brightness):
    """Brightness taking 50 ms a frame: frames come faster than it takes them, and wait for it."""

    def photo_processing(self, frame):
        time.sleep(0.05)
        super().photo_processing(frame)
