"""Target selection in normalized image coordinates -> a region in frame pixels, or a track to lock.

The web page and a MAVLink ground station both describe a selection in the picture they show,
normalized to 0..1 (MAV_CMD_CAMERA_TRACK_RECTANGLE / _POINT use the same convention), so one
conversion serves both: the frame size is the platform's, never the viewer's. A click (a point) inside a track's
box on the newest frame locks that track (:func:`lock_or_roi`); anywhere else, and a dragged rectangle, selects a
region for the processor.
"""

from __future__ import annotations

import math
from typing import Any, Protocol

from uav_tui.errors import CommandError
from uav_tui.flight.commands import Command
from uav_tui.output.text import describe

POINT_BOX_FRACTION = 0.1
"""A single click selects a square this fraction of the frame's shorter side wide."""

MIN_BOX_PX = 4
"""The smallest side of a region sent to the processor."""


def rect_to_roi(x0: float, y0: float, x1: float, y1: float, frame_size: tuple[int, int]) -> tuple[int, int, int, int]:
    """(x, y, w, h) in frame pixels for the normalized rectangle with corners (x0, y0), (x1, y1).

    Corners may come in any order; the result lies inside the frame and is at least MIN_BOX_PX wide.

    Raises:
        CommandError: a coordinate is not a finite number in [0, 1].
    """
    for value in (x0, y0, x1, y1):
        _check_unit(value)
    width, height = frame_size
    left, right = sorted((x0, x1))
    top, bottom = sorted((y0, y1))
    px, py = round(left * width), round(top * height)
    pw, ph = round(right * width) - px, round(bottom * height) - py
    return _fit(px, py, pw, ph, width, height)


def point_to_roi(x: float, y: float, frame_size: tuple[int, int], radius: float = 0.0) -> tuple[int, int, int, int]:
    """A square region centred on the normalized point (x, y).

    Args:
        x: horizontal position, 0 = left edge, 1 = right edge.
        y: vertical position, 0 = top edge, 1 = bottom edge.
        frame_size: (width, height) of the processed frame.
        radius: half the side, as a fraction of the frame width (MAVLink's convention);
            0 picks POINT_BOX_FRACTION of the shorter side.
    """
    for value in (x, y, radius):
        _check_unit(value)
    width, height = frame_size
    side = round(2 * radius * width) if radius > 0 else round(POINT_BOX_FRACTION * min(width, height))
    side = max(MIN_BOX_PX, side)
    return _fit(round(x * width - side / 2), round(y * height - side / 2), side, side, width, height)


class TracksAt(Protocol):
    """Which track a pixel of the newest frame is in (:meth:`uav_tui.flight.track_lock.TrackLock.track_at`)."""

    def track_at(self, x: float, y: float) -> int | None: ...


def lock_or_roi(roi: tuple[int, int, int, int], point: tuple[float, float] | None, frame_size: tuple[int, int],
                tracks: TracksAt) -> Command:
    """``lock ID`` when the normalized ``point`` clicked (already checked) is inside a track's box, else ``roi``."""
    if point is not None:
        track = tracks.track_at(point[0] * frame_size[0], point[1] * frame_size[1])
        if track is not None:
            return Command("lock", (track,))
    return Command("roi", roi)


def roi_from_message(message: Any, frame_size: tuple[int, int]) -> tuple[int, int, int, int]:
    """Validate a page's selection ``{"rect": [x0, y0, x1, y1]}`` or ``{"point": [x, y]}`` and convert it.

    Raises:
        CommandError: the message has neither form, or a value is not a number in [0, 1].
    """
    if not isinstance(message, dict):
        raise CommandError("roi message must be a JSON object with 'rect' or 'point'", key="roi")
    rect, point = message.get("rect"), message.get("point")
    if rect is not None and _numbers(rect, 4):
        x0, y0, x1, y1 = rect
        return rect_to_roi(x0, y0, x1, y1, frame_size)
    if point is not None and _numbers(point, 2):
        x, y = point
        return point_to_roi(x, y, frame_size)
    raise CommandError("roi message needs 'rect': [x0, y0, x1, y1] or 'point': [x, y], numbers in 0..1", key="roi")


def _numbers(value: Any, count: int) -> bool:
    return (isinstance(value, list) and len(value) == count
            and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value))


def _check_unit(value: float) -> None:
    try:  # an int from JSON may have any number of digits: too large for a float
        unit = isinstance(value, int | float) and math.isfinite(value) and 0.0 <= value <= 1.0
    except OverflowError:
        unit = False
    if not unit:
        raise CommandError(f"normalized coordinate {describe(value)} is not a number in 0..1", key="roi")


def _fit(x: int, y: int, w: int, h: int, width: int, height: int) -> tuple[int, int, int, int]:
    """Grow the box to MIN_BOX_PX and move it (never shrink it past the frame) so it lies inside the frame."""
    w, h = min(max(w, MIN_BOX_PX), width), min(max(h, MIN_BOX_PX), height)
    x, y = min(max(x, 0), width - w), min(max(y, 0), height - h)
    return x, y, w, h
