"""One frame through a processor, as every host makes the call: the thread host, the processor's process, eval.

``photo_processing(image)`` timed, then ``getPreparedVector()`` and the output methods (``getLandingTarget()``,
``getGimbalPointing()``: :mod:`processors.outputs`) when asked for, then its ``box``
(:func:`processors.base.read_box`) and ``detections`` (:func:`processors.detections.read_detections`: malformed ones
are the processor's error; each then numbered by the host's :class:`~uav_tui.hosting.tracks.DetectionTracks`); an
exception is caught and kept as text, never raised, so that no
reference to the frame outlives the call (the processor's process reuses a frame's shared-memory slot only
once no view of it is left).
"""

from __future__ import annotations

import time
import traceback
from collections.abc import Callable, Collection
from pathlib import Path
from typing import Any

from processors.base import read_box
from processors.detections import read_detections
from processors.outputs import NO_OUTPUTS, read_outputs
from uav_tui.hosting.tracks import DetectionTracks
from uav_tui.hosting.wire import FrameOutcome


def call_frame(instance: Any, image: Any, *, vector: bool, outputs: Collection[str] = (),
               let_through: tuple[type[BaseException], ...] = (), frame_seq: int | None = None,
               tracks: DetectionTracks | None = None, seen_ns: int | None = None,
               as_data: Callable[[Any], Any] | None = None) -> FrameOutcome:
    """Process ``image`` (the frame ``frame_seq``) with ``instance``; ``vector``: call ``getPreparedVector`` too;
    ``outputs``: these output methods (:func:`processors.outputs.read_outputs`: a value of the wrong type is the
    processor's error; a landing target is stamped with ``frame_seq``); ``tracks``: the processor's tracks, which
    number its ``detections`` as seen at ``seen_ns`` (the frame's capture, monotonic; the call's start when None);
    ``as_data``: what the vector becomes in the record (the processor's process: plain data for the wire).
    Exceptions of the types in ``let_through`` propagate (the processor's process ends on a MemoryError); any other
    is kept in the outcome."""
    start = time.monotonic_ns()
    end, t_vector, found, read, box, detections = 0, 0, None, NO_OUTPUTS, None, None
    try:
        instance.photo_processing(image)
        end = time.monotonic_ns()
        if vector:
            returned = instance.getPreparedVector()
            t_vector = time.monotonic_ns()
            found = returned if as_data is None else as_data(returned)
        read = read_outputs(instance, outputs, frame_seq)
        box = read_box(instance)
        detections = read_detections(instance)
        if tracks is not None:
            detections = tracks.assign(detections, start if seen_ns is None else seen_ns)
    except let_through:
        raise
    except Exception as exc:  # noqa: BLE001 - counted and reported by the caller, never fatal
        return FrameOutcome(start, end or time.monotonic_ns(), t_vector, found, read, box, detections,
                            traceback.format_exc(), describe(exc))
    return FrameOutcome(start, end, t_vector, found, read, box, detections)


def describe(exc: BaseException) -> str:
    """``ValueError: text (file.py:12)``: the exception and the line of the innermost frame that raised it."""
    frames = traceback.extract_tb(exc.__traceback__)
    where = f" ({Path(frames[-1].filename).name}:{frames[-1].lineno})" if frames else ""
    text = " ".join(str(exc).split())[:300]
    return f"{type(exc).__name__}: {text}{where}" if text else f"{type(exc).__name__}{where}"
