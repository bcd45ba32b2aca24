"""The view NanoTrack's template was cut from at selection, to start a NanoTrack anywhere with that same template."""

from __future__ import annotations

import math

import cv2
import numpy as np

from processors.models import create_nanotrack
from processors.steering import Box


def exemplar_side(w: float, h: float) -> int:
    """Side of the square NanoTrack cuts its template from: the box with half its perimeter as context."""
    context = 0.5 * (w + h)
    return max(int(math.sqrt((w + context) * (h + context))), 1)


class SelectedTemplate:
    """The square of the frame around the selected target that ``cv2.TrackerNano.init`` turns into its template.

    ``cv2.TrackerNano`` takes its template from the image it is started on. :meth:`tracker_at` starts one on a
    copy of the current frame with this square pasted (resized to the candidate's size) at a candidate place,
    so the new tracker looks for the target *as it was selected*, from that place: a search elsewhere in the
    frame judged by NanoTrack's own score, with a template that nothing since has changed.
    """

    def __init__(self, work: np.ndarray, box: Box) -> None:
        x, y, w, h = box
        side = exemplar_side(w, h)
        self.view = cv2.getRectSubPix(work, (side, side), (x + w / 2, y + h / 2))
        """The selected target with its context (work-frame pixels, replicated past the frame's edges)."""

    def tracker_at(self, work: np.ndarray, box: Box) -> cv2.TrackerNano:
        """A NanoTrack at ``box`` (work-frame pixels) whose template is the selected view; call ``update`` next."""
        tracker = create_nanotrack()
        tracker.init(self.pasted(work, box), tuple(int(round(v)) for v in box))
        return tracker

    def pasted(self, work: np.ndarray, box: Box) -> np.ndarray:
        """A copy of ``work`` with the selected view (resized to ``box``'s) where a NanoTrack started on ``box``
        cuts its template from."""
        x, y, w, h = box
        side = exemplar_side(w, h)
        patch = cv2.resize(self.view, (side, side), interpolation=cv2.INTER_AREA)
        image = work.copy()
        x0, y0 = int(x + w / 2) - (side + 1) // 2, int(y + h / 2) - (side + 1) // 2  # where init will cut it from
        ix0, iy0 = max(x0, 0), max(y0, 0)
        ix1, iy1 = min(x0 + side, image.shape[1]), min(y0 + side, image.shape[0])
        if ix1 > ix0 and iy1 > iy0:
            image[iy0:iy1, ix0:ix1] = patch[iy0 - y0 : iy1 - y0, ix0 - x0 : ix1 - x0]
        return image
