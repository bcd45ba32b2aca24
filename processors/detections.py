"""The optional ``detections`` attribute: several objects seen in a frame, each a box with a label and a score.

A processor that detects (a YOLO model: people, cars, boats) sets ``self.detections`` to a list of items, each
either an object with ``box``, ``label`` and ``score`` attributes (``processors.detection.Detection`` is one), a
mapping with those keys, or a ``(box, label, score)`` tuple: ``box`` ``(x, y, w, h)`` in frame pixels, ``label`` a
short text, ``score`` in [0, 1]. The platform reads it after every frame, like ``box``, checks it here and
geo-locates each box the same way. Anything malformed is the processor's error for that frame (the message says
which item and what is wrong) and none of that frame's detections is kept, so nothing wrong is recorded.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from processors.base import Box

MAX_DETECTIONS = 32
"""At most this many detections a frame: more is the processor's error (report the most confident first and cut,
``detections[:32]``). It bounds what crosses to the platform, is recorded and geo-located per frame."""

MAX_LABEL_CHARS = 64
"""A longer label is the processor's error: a label is a class name, not a description."""


@dataclass(frozen=True, slots=True)
class Detected:
    """One checked detection: whole frame pixels, a label, a score in [0, 1]."""

    box: Box
    label: str
    score: float


def read_detections(instance: object) -> tuple[Detected, ...] | None:
    """The processor's ``detections`` attribute, checked; None when it has none (absent or None).

    Raises:
        TypeError, ValueError: not a list of detections, more than :data:`MAX_DETECTIONS`, or an item that is not
            a box with a label and a score (the message names the item and what is wrong).
    """
    value = getattr(instance, "detections", None)
    if value is None:
        return None
    if isinstance(value, str | bytes | Mapping) or not isinstance(value, Sequence):
        raise TypeError(f"detections is {type(value).__name__}: set a list of (box, label, score) or None")
    if len(value) > MAX_DETECTIONS:
        raise ValueError(f"detections has {len(value)} items, at most {MAX_DETECTIONS} are taken: put the most "
                         f"confident first and cut (detections[:{MAX_DETECTIONS}])")
    return tuple(_checked(index, item) for index, item in enumerate(value))


def _checked(index: int, item: Any) -> Detected:
    where = f"detections[{index}]"
    box: Any
    label: Any
    score: Any
    if isinstance(item, Mapping):
        box, label, score = item.get("box"), item.get("label"), item.get("score")
    elif all(hasattr(item, name) for name in ("box", "label", "score")):
        box, label, score = item.box, item.label, item.score
    elif isinstance(item, tuple | list) and len(item) == 3:
        box, label, score = item
    else:
        raise TypeError(f"{where} is {type(item).__name__} {item!r:.60}: expected (box, label, score) or an object "
                        "with box, label and score")
    if not isinstance(label, str) or not 0 < len(label) <= MAX_LABEL_CHARS:
        raise ValueError(f"{where}: label {label!r:.80} must be a text of 1 to {MAX_LABEL_CHARS} characters")
    try:
        number = float(score)
    except (TypeError, ValueError):
        raise TypeError(f"{where}: score {score!r:.60} is not a number") from None
    if not 0.0 <= number <= 1.0:  # NaN fails too
        raise ValueError(f"{where}: score {number!r} must be in [0, 1]")
    return Detected(_box(where, box), label, number)


def _box(where: str, box: Any) -> Box:
    try:
        x, y, w, h = (float(v) for v in box)
    except (TypeError, ValueError, OverflowError):
        raise TypeError(f"{where}: box {box!r:.60} is not 4 numbers (x, y, w, h)") from None
    if not all(math.isfinite(v) and abs(v) < 1e7 for v in (x, y, w, h)) or w <= 0 or h <= 0:
        raise ValueError(f"{where}: box {(x, y, w, h)!r} must be finite with a positive width and height")
    return round(x), round(y), max(1, round(w)), max(1, round(h))
