"""Test processors, loaded by file path (``tests/tui/procs.py:RecordingProcessor``) as a researcher's would be."""

import numpy as np


class RecordingProcessor:
    """Remembers every operator call; never moves the vehicle."""

    def __init__(self):
        self.tmMgr = None
        self.frames = 0
        self.buttons = []
        self.rois = []

    def photo_processing(self, frame):
        self.frames += 1
        self.mean = float(np.mean(frame))

    def catch_cmd(self, roi):
        self.rois.append(tuple(roi))

    def customize_processing(self, id):
        self.buttons.append(id)
