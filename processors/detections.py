"""The optional ``detections`` attribute: several objects seen in a frame, each a box with a label and a score.

A processor that detects (a YOLO model: people, cars, boats) sets ``self.detections`` to a list of items, each
either an object with ``box``, ``label`` and ``score`` attributes (``processors.detection.Detection`` is one), a
mapping with those keys, or a ``(box, label, score)`` tuple: ``box`` ``(x, y, w, h)`` in frame pixels, ``label`` a
short text, ``score`` in [0, 1]. The platform reads it after every frame, like ``box``, checks it here and
geo-locates each box the same way. Anything malformed is the processor's error for that frame (the message says
which item and what is wrong) and none of that frame's detections is kept, so nothing wrong is recorded.

Each detection may carry its own ``track_id`` (an attribute or key, or a fourth tuple item): a whole number in
``[0, MAX_TRACK_ID)``, no two alike in a frame. Without one the platform's tracker gives it one
(:mod:`uav_tui.hosting.tracks`); a frame where any detection has a ``track_id`` is taken as the processor's tracks.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from uav_values.box import PixelBox
from uav_values.detections import Detected

MAX_DETECTIONS = 32
"""At most this many detections a frame: more is the processor's error (report the most confident first and cut,
``detections[:32]``). It bounds what crosses to the platform, is recorded and geo-located per frame."""

MAX_TRACK_ID = 1_000_000
"""A processor's own ``track_id`` is a whole number below this; anything else is the processor's error."""

MAX_LABEL_CHARS = 64
"""A longer label is the processor's error: a label is a class name, not a description."""


def read_detections(instance: object) -> tuple[Detected, ...] | None:
    """The processor's ``detections`` attribute, checked; None when it has none (absent or None).

    Raises:
        TypeError, ValueError: not a list of detections, more than :data:`MAX_DETECTIONS`, or an item that is not
            a box with a label and a score (the message names the item and what is wrong).
    """
    value = getattr(instance, "detections", None)  # optional: see processors.base.FrameProcessor
    if value is None:
        return None
    if isinstance(value, str | bytes | Mapping) or not isinstance(value, Sequence):
        raise TypeError(f"detections is {type(value).__name__}: set a list of (box, label, score) or None")
    if len(value) > MAX_DETECTIONS:
        raise ValueError(f"detections has {len(value)} items, at most {MAX_DETECTIONS} are taken: put the most "
                         f"confident first and cut (detections[:{MAX_DETECTIONS}])")
    found = tuple(_checked(index, item) for index, item in enumerate(value))
    ids = [d.track_id for d in found if d.track_id is not None]
    if len(set(ids)) < len(ids):
        twice = next(i for i in ids if ids.count(i) > 1)
        raise ValueError(f"detections: track_id {twice} is on two detections of one frame: one object, one track")
    return found


def _checked(index: int, item: Any) -> Detected:
    where = f"detections[{index}]"
    box: Any
    label: Any
    score: Any
    track: Any = None
    if isinstance(item, Mapping):
        box, label, score, track = item.get("box"), item.get("label"), item.get("score"), item.get("track_id")
    elif all(hasattr(item, name) for name in ("box", "label", "score")):  # processors.detection.Detection, or alike
        box, label, score, track = item.box, item.label, item.score, getattr(item, "track_id", None)
    elif isinstance(item, tuple | list) and len(item) in (3, 4) and not isinstance(item[0], int | float | np.number):
        box, label, score, track = (*item, None)[:4]
    else:
        raise TypeError(f"{where} is {type(item).__name__} {item!r:.60}: expected (box, label, score[, track_id]) "
                        "or an object with box, label and score")
    if not isinstance(label, str) or not 0 < len(label) <= MAX_LABEL_CHARS:
        raise ValueError(f"{where}: label {label!r:.80} must be a text of 1 to {MAX_LABEL_CHARS} characters")
    try:
        number = float(score)
    except (TypeError, ValueError):
        raise TypeError(f"{where}: score {score!r:.60} is not a number") from None
    if not 0.0 <= number <= 1.0:  # NaN fails too
        raise ValueError(f"{where}: score {number!r} must be in [0, 1]")
    return Detected(_box(where, box), label, number, track_id=_track_id(where, track))


def _track_id(where: str, track: Any) -> int | None:
    if track is None:
        return None
    if isinstance(track, bool) or not isinstance(track, int | np.integer) or not 0 <= track < MAX_TRACK_ID:
        raise ValueError(f"{where}: track_id {track!r:.60} must be a whole number in [0, {MAX_TRACK_ID}) or None")
    return int(track)


def _box(where: str, box: Any) -> PixelBox:
    try:
        x, y, w, h = (float(v) for v in box)
    except (TypeError, ValueError, OverflowError):
        raise TypeError(f"{where}: box {box!r:.60} is not 4 numbers (x, y, w, h)") from None
    if not all(math.isfinite(v) and abs(v) < 1e7 for v in (x, y, w, h)) or w <= 0 or h <= 0:
        raise ValueError(f"{where}: box {(x, y, w, h)!r} must be finite with a positive width and height")
    return round(x), round(y), max(1, round(w)), max(1, round(h))
