"""The platform's overlay of the tracks: each detection's number below its box, the locked track's box and vector.

The processor draws its own overlay while it processes a frame, before the platform numbers its detections
(:mod:`uav_tui.hosting.tracks`); this is drawn after, on the loop, once the lock has steered and before the frame
reaches the web page, the TUI and the saved images (the frame listeners). The numbers go below the boxes (a
detector's label is above them), in OpenCV's plain Hershey text without anti-aliasing (3 us a number; 12-33 us with
it). Measured (scripts/bench_lock.py): 20-40 us for three numbers and the locked box, 100-125 us for 32.
"""

from __future__ import annotations

import cv2
import numpy as np

from processors.steering import Vector, draw_target
from uav_tui.flight.track_lock import LockState, LockStatus
from uav_values.detections import Detected

NUMBER_COLOUR = (0, 255, 255)
"""BGR: the numbers in yellow (a detector's boxes are orange, a tracker's green)."""

LOCK_COLOUR = (0, 0, 255)
"""BGR: the locked track in red."""


def draw_tracks(image: np.ndarray, detections: tuple[Detected, ...] | None, lock: LockStatus,
                vector: Vector | None) -> None:
    """Draw, in place, the number of each of ``detections`` that has one and, while locked, the locked track's box
    with ``vector`` (or, while it is lost, that it is)."""
    locked = None
    for found in detections or ():
        if found.track_id is None:
            continue
        x, y, w, h = found.box
        cv2.putText(image, f"#{found.track_id}", (x, min(y + h + 12, image.shape[0] - 2)), cv2.FONT_HERSHEY_SIMPLEX,
                    0.45, NUMBER_COLOUR, 1, cv2.LINE_8)
        if lock.state is LockState.LOCKED and found.track_id == lock.track_id:
            locked = found
    if locked is not None:
        draw_target(image, locked.box, vector, LOCK_COLOUR, f"LOCK #{locked.track_id}")
    elif lock.state is LockState.LOST:
        cv2.putText(image, f"LOCK {lock}", (8, 44), cv2.FONT_HERSHEY_SIMPLEX, 0.6, LOCK_COLOUR, 2,
                    cv2.LINE_8)
