"""Objects seen in a frame: what a detector found (:class:`Detection`) and what the platform kept
(:class:`Detected`)."""

from __future__ import annotations

from dataclasses import dataclass, field

from uav_values.box import Box, PixelBox


@dataclass(frozen=True)
class Detection:
    """One detected object: box (x, y, w, h) in frame pixels, confidence 0..1, class id and name."""

    box: Box
    score: float
    class_id: int
    label: str


@dataclass(frozen=True, slots=True)
class Detected:
    """One checked detection: whole frame pixels, a label, a score in [0, 1], and the track it belongs to."""

    box: PixelBox
    label: str
    score: float
    track_id: int | None = field(default=None, kw_only=True)
    """The same number on every frame for the same object (the processor's, or the platform's tracker's); None
    while the tracker has not made it a track (a first low-score sighting)."""
