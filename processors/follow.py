"""What the tracking processors share: selecting a target, the F1-F4 buttons, the vector (or the gimbal rates)
towards it, the overlay.

:class:`TargetFollower` implements the published methods (``catch_cmd``, ``customize_processing``,
``getPreparedVector``, ``getGimbalPointing``, ``photo_processing``) once; a tracker (``csrt``, ``nanotrack``)
supplies the tracking through four hooks and the ``box``/``selected`` properties.
"""

from __future__ import annotations

import logging

import cv2
import numpy as np

from processors.frame_telemetry import FrameTelemetry, frame_time_s
from processors.gimbal_steering import GimbalSteering
from processors.steering import Ramp, Steering, Vector, as_box, draw_target
from uav_values.box import Box
from uav_values.gimbal import GimbalPointing

logger = logging.getLogger(__name__)

MIN_ROI = 4
"""Shortest side, in frame pixels, of a selection that is taken."""

FOLLOW_GAIN = 2.0
"""The trackers' default steering gain (m/s per normalised offset). Following a target that moves at ``v`` m/s, a
proportional follower settles with it ``v / gain`` of the half-frame off centre, whatever the height: at the former
0.8 a 1 m/s car (the ``sim:`` demo's) sat at 1.25, out of the frame, and the quick start lost it at its edge; at 2
it sits half-way out, and a 1 m/s target is what ``max_speed`` lets the vehicle follow anyway."""

FOLLOW_MODES = ("vehicle", "gimbal")
"""What keeps the target centred: the vehicle's vectors, or the gimbal's rates while the vehicle holds."""


class TargetFollower:
    """Target selection, steering, F1-F4 and overlay around a tracker's hooks.

    A subclass implements ``_start(frame, roi) -> bool`` (begin tracking ``roi``, full-frame pixels, already
    clipped to the frame; False when it cannot), ``_track(frame)`` (one frame while a target is selected),
    ``_drop()`` (forget the target) and ``_search_now()`` (look for the target on the next frame), and the
    ``box`` (full-frame pixels, None while lost) and ``selected`` properties. ``score`` is drawn beside the box.

    Vector: body-frame velocity (vx forward, vy right, m/s, clamped to ``max_speed`` <= 1, eased in by
    :class:`~processors.steering.Ramp`) that moves the
    vehicle so that the target comes to the frame centre (``camera="down"``), or keeps it centred
    horizontally and at its selection-time size (``camera="forward"``); ``t`` = ``vector_t`` s.
    ``getPreparedVector`` returns None when no target is selected or it is lost.

    ``follow="gimbal"``: the vehicle holds (no vector) and ``getGimbalPointing`` returns the rates that turn the
    gimbal towards the target (:class:`~processors.gimbal_steering.GimbalSteering`: ``gimbal_gain`` deg/s per
    degree off centre, at most ``gimbal_max_rate``); None when no target is tracked (the platform stops the gimbal).

    Operator buttons:
        F1: drop the target (stop following).
        F2: search for the target now (on the next frame, even while tracking).
        F3: gain x 1.25.
        F4: gain / 1.25.
    """

    def __init__(self, camera: str, gain: float, dead_band: float, max_speed: float, vector_t: float, *,
                 follow: str = "vehicle", gimbal_gain: float = 2.0, gimbal_max_rate: float = 60.0) -> None:
        if follow not in FOLLOW_MODES:
            raise ValueError(f"follow must be one of {', '.join(FOLLOW_MODES)}, got {follow!r}")
        self.tmMgr: FrameTelemetry | None = None
        self.steering = Steering(camera, gain, dead_band, max_speed, vector_t)
        self._ramp = Ramp()
        self.follow = follow
        self.gimbal_steering = GimbalSteering(gimbal_gain, max_rate=gimbal_max_rate)
        self._pointing: GimbalPointing | None = None
        self.score = 0.0
        """The tracker's confidence in the last box (diagnostics, drawn beside it)."""
        self._pending_roi: Box | None = None
        self._ref_height = 0.0
        self._vector: Vector | None = None
        self._shrink = 1
        """The tracker works on the frame shrunk by this whole factor (boxes stay in full-frame pixels)."""
        self._force_search = False
        """Set by F2: the tracker searches for the target on the next frame."""
        self._templates: list[np.ndarray] = []
        """The target's appearance (work-frame pixels); empty when nothing is selected."""
        self._work_box: Box | None = None
        """Work-frame pixels: the last box accepted as the target."""
        self._tracking = False
        """False while the selected target is lost."""
        self._evidence = 0
        """Frames of loss evidence in a row."""
        self._lost_frames = 0

    # ---- contract -------------------------------------------------------------------------------
    def photo_processing(self, frame: np.ndarray) -> None:
        """Start or update the tracker on ``frame``, prepare the vector and draw the overlay on it in place."""
        if self._pending_roi is not None:
            roi, self._pending_roi = self._clip(self._pending_roi, frame), None
            if roi is not None and self._start(frame, roi):
                self._ref_height = roi[3]
        elif self.selected:
            self._track(frame)
        box = self.box
        size = (frame.shape[1], frame.shape[0])
        if self.follow == "gimbal":
            self._vector = None
            self._pointing = self._gimbal_rates(box, size) if box else None
        else:
            vector = self.steering.vector(box, size, self._ref_height) if box else None
            self._vector = self._ramp(vector, frame_time_s(self.tmMgr))
        self._draw(frame, box)

    def catch_cmd(self, roi: tuple[int, int, int, int]) -> None:
        """Select the target: ``roi`` = (x, y, w, h) in frame pixels; tracking starts on the next frame."""
        x, y, w, h = (float(v) for v in roi)
        if w < MIN_ROI or h < MIN_ROI:
            logger.warning("%s: ROI %s too small, ignored", type(self).__name__, roi)
            return
        self._pending_roi = (x, y, w, h)

    def customize_processing(self, id: int) -> None:  # noqa: A002 - published name
        """F1 drop target, F2 search now, F3 gain up, F4 gain down."""
        if id == 1:
            self._drop()
            self._vector = self._pointing = None
            logger.info("%s: target dropped", type(self).__name__)
        elif id == 2:
            self._search_now()
        elif id == 3:
            self.steering.scale_gain(1.25)
        elif id == 4:
            self.steering.scale_gain(1 / 1.25)

    def getPreparedVector(self) -> Vector | None:
        """(vx, vy, t) towards the target, or None when there is no tracked target (or ``follow="gimbal"``)."""
        return self._vector

    def getGimbalPointing(self) -> GimbalPointing | None:
        """With ``follow="gimbal"``, the rates that turn the gimbal towards the target; else, or untracked, None."""
        return self._pointing

    # ---- state ----------------------------------------------------------------------------------
    @property
    def box(self) -> Box | None:
        """Tracked box (x, y, w, h) in full-frame pixels, None when lost or idle."""
        if not self._tracking or self._work_box is None:
            return None
        return as_box(v * self._shrink for v in self._work_box)

    @property
    def selected(self) -> bool:
        """True while a target is selected (tracked or lost)."""
        return bool(self._templates)

    @property
    def lost(self) -> bool:
        """True while a target is selected but not currently tracked."""
        return self.selected and self.box is None

    # ---- hooks ----------------------------------------------------------------------------------
    def _start(self, frame: np.ndarray, roi: Box) -> bool:
        raise NotImplementedError

    def _track(self, frame: np.ndarray) -> None:
        raise NotImplementedError

    def _drop(self) -> None:
        raise NotImplementedError

    def _search_now(self) -> None:
        self._force_search = True

    # ---- internals ------------------------------------------------------------------------------
    def _gimbal_rates(self, box: Box, size: tuple[int, int]) -> GimbalPointing:
        """Rates towards ``box`` with the frame's camera model and the gimbal's pitch at its capture, when known."""
        tm = self.tmMgr
        camera = tm.camera() if tm is not None else None
        pitch = tm.snapshot().gimbal_pitch_deg if tm is not None else None
        return self.gimbal_steering.rates(box, size, camera, None if pitch is None else float(pitch))

    def _work_frame(self, frame: np.ndarray) -> np.ndarray:
        """``frame`` shrunk by ``_shrink``: INTER_AREA on whole k x k blocks, its fast path."""
        k = self._shrink
        if k == 1:
            return frame
        h, w = frame.shape[0] // k, frame.shape[1] // k
        return cv2.resize(frame[: h * k, : w * k], (w, h), interpolation=cv2.INTER_AREA)

    def _clip(self, roi: Box, frame: np.ndarray) -> Box | None:
        fh, fw = frame.shape[:2]
        x0, y0 = max(roi[0], 0.0), max(roi[1], 0.0)
        x1, y1 = min(roi[0] + roi[2], float(fw)), min(roi[1] + roi[3], float(fh))
        if x1 - x0 < MIN_ROI or y1 - y0 < MIN_ROI:
            logger.warning("%s: ROI %s is outside the %dx%d frame, ignored", type(self).__name__, roi, fw, fh)
            return None
        return x0, y0, x1 - x0, y1 - y0

    def _draw(self, frame: np.ndarray, box: Box | None) -> None:
        if box is not None:
            draw_target(frame, box, self._vector, (0, 255, 0), f"{self.score:.2f}")
        elif self.selected:
            cv2.putText(frame, "LOST - searching", (8, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (0, 0, 255), 2)
