"""The smallest useful processor, as in the paper: the mean brightness of each frame.

Copy this file to start your own: ``uav-tui --processor ~/algos/mine.py:MyAnalyzer``.
"""

import numpy as np


class MeanBrightnessProcessor:
    """Measures mean brightness and saves every 30th frame with it into the flight dataset.

    It never returns a vector, so it never moves the vehicle.
    """

    def __init__(self, save_every=30):
        self.tmMgr = None  # set by the platform: telemetry and the dataset recorder
        self.save_every = save_every
        self.brightness = None
        self.frames = 0

    def photo_processing(self, frame):
        self.brightness = float(np.mean(frame))
        self.frames += 1
        if self.tmMgr is not None and self.frames % self.save_every == 0:
            self.tmMgr.save(frame, brightness=self.brightness)
