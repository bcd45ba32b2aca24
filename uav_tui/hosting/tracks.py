"""The platform's multi-object tracker: a stable ``track_id`` for each of a processor's ``detections``.

Every host runs it on the processor's side, right after the frame's ``detections`` are checked
(:func:`uav_tui.hosting.frame_call.call_frame`), so any processor that detects gets tracks (a researcher's own
detector too) and the cost is the processor's worker's, never the event loop's. The tracking is ByteTrack from
``edgefirst-tracker`` (Apache-2.0, Au-Zone's EdgeFirst HAL: Kalman prediction and IoU association in Rust, numpy its
only dependency, wheels for aarch64). It names tracks with UUIDs; here each becomes a small number, counted up from 0
in the order the tracks appeared. A frame whose detections carry their own ``track_id`` is the processor's
tracking and is left as it is.

The library's Kalman filter steps once per call, not per elapsed time (measured: two cars crossing during ten
frames with nothing detected keep both ids when those frames are passed on empty, lose both when they are left
out), so :meth:`DetectionTracks.assign` is called on every frame processed without error, also one with nothing
(or None) detected; frames the platform skipped (newest frame wins) stretch a step. The timestamps drop tracks
unseen for :data:`KEEP_LOST_S`.
"""

from __future__ import annotations

import zlib
from dataclasses import replace

import numpy as np
from edgefirst.tracker import ByteTrack

from processors.detections import MAX_TRACK_ID
from uav_values.detections import Detected

NEW_TRACK_SCORE = 0.25
"""A detection at least this confident may start a track; a less confident one only continues one (ByteTrack's
second pass). The shipped ``yolo`` reports nothing below 0.25."""

KEEP_LOST_S = 2.0
"""A track not seen for this long is dropped; one seen again sooner (a target behind a tree for a second) keeps its
id. Its box is predicted meanwhile from its motion."""

MATCH_IOU = 0.1
"""The overlap of a detection with a track's predicted box below which they are not matched. The library's 0.25
loses cars the ``sim:`` camera sees at 10 fps after a 1 s gap (tests/hosting/test_tracks.py), 0.1 keeps them."""

KALMAN_UPDATE = 0.5
"""How far each match moves a track's state to the detection (the library's 0.25 follows a turning car late)."""

_NAMES_KEPT = 256
"""Past this many known UUIDs, the ones of tracks no longer alive are forgotten (bounded memory on a long flight)."""


class DetectionTracks:
    """One processor's tracks: :meth:`assign` each frame's detections, in capture order."""

    def __init__(self, first_id: int = 0) -> None:
        """``first_id``: the number of the first track (a restarted processor's go on from its last)."""
        self._tracker = ByteTrack(high_conf=NEW_TRACK_SCORE, iou=MATCH_IOU, update=KALMAN_UPDATE,
                                   lifespan_ns=int(KEEP_LOST_S * 1e9))
        self._ids: dict[str, int] = {}
        self._next_id = first_id % MAX_TRACK_ID
        self._started = False
        """A detection was seen: from then on every frame updates the tracker (before, it has nothing to age)."""

    def assign(self, detections: tuple[Detected, ...] | None, at_ns: int) -> tuple[Detected, ...] | None:
        """``detections`` (seen at ``at_ns``, monotonic) each with its ``track_id``; None stays None (a processor
        without the attribute, or one that set None: its tracks age as on a frame with nothing seen)."""
        if detections is not None and any(found.track_id is not None for found in detections):
            return detections
        found = detections or ()
        if not (found or self._started):
            return detections  # a processor that reports no detections pays nothing (10 us a frame otherwise)
        self._started = True
        boxes = np.array([(x, y, x + w, y + h) for (x, y, w, h) in (d.box for d in found)], np.float32).reshape(-1, 4)
        scores = np.array([d.score for d in found], np.float32)
        labels = np.array([zlib.crc32(d.label.encode()) for d in found], np.uint64)
        tracks = self._tracker.update(boxes, scores, labels, at_ns)
        if len(self._ids) > _NAMES_KEPT:
            alive = {active.info.uuid for active in self._tracker.get_active_tracks()}
            self._ids = {name: number for name, number in self._ids.items() if name in alive}
        if detections is None:
            return None
        return tuple(replace(d, track_id=None if track is None else self._number(track.uuid))
                     for d, track in zip(detections, tracks, strict=True))

    def _number(self, name: str) -> int:
        number = self._ids.get(name)
        if number is None:
            number = self._ids[name] = self._next_id
            self._next_id = (self._next_id + 1) % MAX_TRACK_ID
        return number
