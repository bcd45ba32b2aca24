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


class DetectingProcessor(RecordingProcessor):
    """A RecordingProcessor that detects one car in the frame's top-left quarter on every frame."""

    def __init__(self):
        super().__init__()
        self.detections = [((0, 0, 320, 240), "car", 0.9)]


class SteeringProcessor(RecordingProcessor):
    """A RecordingProcessor with a vector method (never a vector): autonomy may go on."""

    def getPreparedVector(self):
        return None


class PrintingProcessor:
    """Prints as a researcher debugging does: a line every 30 frames; F-key N prints N * 100 lines at once, the
    first with a terminal escape in it."""

    def __init__(self):
        self.frames = 0

    def photo_processing(self, frame):
        self.frames += 1
        if self.frames % 30 == 0:
            print(f"hello from the processor, frame {self.frames}")

    def customize_processing(self, id):
        print("\x1b[2Jcleared?")
        for n in range(1, id * 100):
            print("line", n)


class DescribedButtons(RecordingProcessor):
    """Says what its buttons do, as the built-in processors do.

    Operator buttons:
        F1: mark the spot.
        F3: forget the spot.
    """


class MisspeltVector(RecordingProcessor):
    """Meant to steer, but the platform never calls getPreparedVectr."""

    def getPreparedVectr(self):
        return (1.0, 0.0, 1.0)


class Flooding(RecordingProcessor):
    """F4 prints 20,000 lines at once, as a debugging loop does."""

    def customize_processing(self, id):
        for n in range(20000):
            print("flood", n)
