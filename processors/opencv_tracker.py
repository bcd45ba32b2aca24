"""A plain OpenCV tracker as a processor: the baseline ``uav-tui eval`` scores others against (``cv:NAME``)."""

from __future__ import annotations

import logging
from typing import Any

import cv2
import numpy as np

from processors.models import nanotrack_files
from processors.steering import as_box
from uav_values.box import Box

logger = logging.getLogger(__name__)

_SHIPPED_MODELS = {"nano": nanotrack_files}
"""Trackers whose default parameters name the models that ship with the package (see :mod:`processors.models`)."""


def available_trackers() -> dict[str, tuple[Any, str]]:
    """Lower-case name -> (namespace, OpenCV name) of every tracker the installed OpenCV has.

    ``cv2.TrackerCSRT_create`` gives ``"csrt"``; ``cv2.legacy`` trackers not in ``cv2`` itself are included.
    """
    found: dict[str, tuple[Any, str]] = {}
    for namespace in (cv2, getattr(cv2, "legacy", None)):
        for attr in dir(namespace) if namespace is not None else ():
            if attr.startswith("Tracker") and attr.endswith("_create"):
                stem = attr[len("Tracker"):-len("_create")]
                found.setdefault(stem.lower(), (namespace, stem))
    return found


class OpenCVTracker:
    """OpenCV's ``Tracker<NAME>`` with its defaults (or ``params``), behind the processor contract.

    ``catch_cmd(roi)`` starts the tracker on the next frame; ``photo_processing`` updates it and draws
    the box. ``box`` is the tracker's box, or None when it reports failure (it keeps trying). ``nano``
    loads the NanoTrack v2 models shipped in :mod:`processors.models` unless ``backbone``/``neckhead`` are given.

    Args:
        tracker: lower-case OpenCV name (``csrt``, ``kcf``, ``mil``, ...; see :func:`available_trackers`).
        **params: fields of ``Tracker<NAME>_Params`` to change from OpenCV's defaults.
    """

    def __init__(self, tracker: str = "csrt", **params: Any) -> None:
        factories = available_trackers()
        if tracker not in factories:
            raise ValueError(f"OpenCV has no tracker {tracker!r}; this build has {', '.join(sorted(factories))}")
        self.tmMgr = None
        self.name = tracker
        self._namespace, self._stem = factories[tracker]
        self._params = {**(_SHIPPED_MODELS[tracker]() if tracker in _SHIPPED_MODELS else {}), **params}
        self._create()  # a wrong parameter fails here, at load time
        self._tracker: Any = None
        self._pending: Box | None = None
        self.box: Box | None = None
        """What the tracker reported for the last frame, None when it failed or nothing is selected."""

    def catch_cmd(self, roi: tuple[int, int, int, int]) -> None:
        """Start tracking ``roi`` (x, y, w, h, frame pixels) on the next frame."""
        self._pending = as_box(roi)

    def photo_processing(self, frame: np.ndarray) -> None:
        """Update the tracker on ``frame`` and draw its box in place."""
        if self._pending is not None:
            self._tracker = self._create()
            self._tracker.init(frame, tuple(int(round(v)) for v in self._pending))
            self.box, self._pending = self._pending, None
        elif self._tracker is not None:
            ok, found = self._tracker.update(frame)
            self.box = as_box(found) if ok else None
        if self.box is not None:
            x, y, w, h = (int(round(v)) for v in self.box)
            cv2.rectangle(frame, (x, y), (x + w, y + h), (0, 255, 0), 2)

    def _create(self) -> Any:
        create = getattr(self._namespace, f"Tracker{self._stem}_create")
        if not self._params:
            return create()
        params_type = getattr(self._namespace, f"Tracker{self._stem}_Params", None)
        if params_type is None:
            raise ValueError(f"OpenCV tracker {self.name!r} takes no parameters")
        params = params_type()
        for key, value in self._params.items():
            if not hasattr(params, key):
                raise ValueError(f"Tracker{self._stem}_Params has no field {key!r}")
            setattr(params, key, value)
        return create(params)
