"""CSRT tracker with SIFT re-acquisition: follows an operator-selected target."""

from __future__ import annotations

import logging
from typing import Any

import cv2
import numpy as np

from processors import sift_match
from processors.steering import Box, Steering, Vector, draw_target

logger = logging.getLogger(__name__)

_PATCH = 32
"""Side of the grayscale patch used for the appearance check (pixels)."""

_MODES: dict[str, dict[str, Any]] = {
    # lighter CSRT (no segmentation / colour names, fewer ADMM iterations and scales: the template
    # size, which decides accuracy, is kept), SIFT on a 320-px-wide frame, capped features,
    # search every other frame while lost
    "fast": {
        "sift_width": 320,
        "sift_features": 1500,
        "reacquire_every": 2,
        "csrt": {
            "use_segmentation": False,
            "use_color_names": False,
            "admm_iterations": 2,
            "number_of_scales": 17,
        },
    },
    # the paper: default CSRT, SIFT at full resolution, unlimited features, search every frame
    "paper": {"sift_width": 0, "sift_features": 0, "reacquire_every": 1, "csrt": {}},
}


def _patch(gray: np.ndarray, box: Box) -> np.ndarray | None:
    x, y, w, h = (int(round(v)) for v in box)
    x0, y0 = max(x, 0), max(y, 0)
    x1, y1 = min(x + w, gray.shape[1]), min(y + h, gray.shape[0])
    if x1 - x0 < 4 or y1 - y0 < 4:
        return None
    p = cv2.resize(gray[y0:y1, x0:x1], (_PATCH, _PATCH), interpolation=cv2.INTER_AREA).astype(np.float32)
    p -= p.mean()
    n = float(np.linalg.norm(p))
    return p / n if n > 1e-6 else None


def _similarity(a: np.ndarray | None, b: np.ndarray | None) -> float:
    return float((a * b).sum()) if a is not None and b is not None else 0.0


_ADAPT_ABOVE = 0.6
"""Similarity above which the tracked patch is blended into the adaptive appearance template."""

_ADAPT_RATE = 0.1
"""Weight of the newest patch in the adaptive template."""


class CSRTTrackingProcessor:
    """Track an operator-selected target with CSRT; re-acquire it with SIFT when it is lost.

    ``catch_cmd(roi)`` starts a CSRT tracker on the region and stores its appearance (SIFT keypoints
    and a normalised grayscale patch). Each frame updates the tracker; the target counts as lost when
    CSRT reports failure or the appearance similarity of the tracked box (normalised cross-correlation
    with the selected patch, or with a slowly adapted copy of it) collapses (occlusion, drift).
    While lost, SIFT matching against the stored appearance (ratio test + RANSAC homography)
    searches the frame and re-initialises the tracker on success.

    Vector: body-frame velocity (vx forward, vy right, m/s, clamped to ``max_speed`` <= 1) that
    moves the vehicle so that the target comes to the frame centre (``camera="down"``), or keeps it
    centred horizontally and at its selection-time size (``camera="forward"``); ``t`` =
    ``vector_t`` s. ``getPreparedVector`` returns None when no target is selected or it is lost.

    Operator buttons:
        F1: drop the target (stop following).
        F2: re-acquire now (run the SIFT search on the next frame, even while tracking).
        F3: gain x 1.25.
        F4: gain / 1.25.

    Args:
        mode: "fast" (lighter CSRT, SIFT on a downscaled frame with capped features) or "paper"
            (default CSRT, full-resolution unlimited SIFT, search every frame while lost).
        camera: "down" or "forward".
        gain, dead_band, max_speed, vector_t: steering (see processors.steering.Steering).
        min_similarity: appearance similarity (-1..1) below which the target counts as lost.
        min_inliers: RANSAC inliers needed to re-acquire.
        ratio: Lowe's ratio-test threshold.
        sift_width, sift_features, reacquire_every: override the mode's values (0 = full width /
            unlimited features).
    """

    def __init__(
        self,
        mode: str = "fast",
        camera: str = "down",
        gain: float = 0.8,
        dead_band: float = 0.05,
        max_speed: float = 1.0,
        vector_t: float = 0.5,
        min_similarity: float = 0.3,
        min_inliers: int = 8,
        ratio: float = 0.75,
        sift_width: int | None = None,
        sift_features: int | None = None,
        reacquire_every: int | None = None,
    ) -> None:
        if mode not in _MODES:
            raise ValueError(f"mode must be one of {sorted(_MODES)}, got {mode!r}")
        cfg = dict(_MODES[mode])
        overrides = {"sift_width": sift_width, "sift_features": sift_features}
        overrides["reacquire_every"] = reacquire_every
        cfg.update({k: v for k, v in overrides.items() if v is not None})
        self.tmMgr = None
        self.mode = mode
        self.steering = Steering(camera, gain, dead_band, max_speed, vector_t)
        self.min_similarity = min_similarity
        self.min_inliers = min_inliers
        self.ratio = ratio
        self._cfg = cfg
        self._sift = sift_match.make_sift(cfg["sift_features"])
        self._tracker: cv2.Tracker | None = None
        self._pending_roi: Box | None = None
        self._ref_feat: sift_match.Features | None = None  # SIFT-frame pixels
        self._ref_box: Box | None = None  # SIFT-frame pixels, where the reference features were taken
        self._ref_patch: np.ndarray | None = None  # appearance at selection
        self._recent_patch: np.ndarray | None = None  # slowly adapted appearance (pose, light)
        self._ref_height = 0.0
        self._box: Box | None = None  # frame pixels; None = lost / no target
        self._frame_size = (0, 0)
        self._lost_frames = 0
        self._force_search = False
        self._vector: Vector | None = None
        self.similarity = 0.0
        """Appearance similarity of the last tracked box (diagnostics)."""

    # ---- contract -------------------------------------------------------------------------------
    def photo_processing(self, frame: np.ndarray) -> None:
        """Update the tracker on ``frame`` and draw the overlay on it in place."""
        self._frame_size = (frame.shape[1], frame.shape[0])
        gray = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        if self._pending_roi is not None:
            self._start(frame, gray, self._pending_roi)
            self._pending_roi = None
        elif self._ref_feat is not None:
            if self._box is not None:
                self._update(frame, gray)
            if self._box is None or self._force_search:
                self._lost_frames += 1
                if self._force_search or (self._lost_frames - 1) % max(self._cfg["reacquire_every"], 1) == 0:
                    self._reacquire(frame, gray)
        box = self._box
        self._vector = self.steering.vector(box, self._frame_size, self._ref_height) if box else None
        self._draw(frame)

    def catch_cmd(self, roi: tuple[int, int, int, int]) -> None:
        """Select the target: ``roi`` = (x, y, w, h) in frame pixels; tracking starts on the next frame."""
        x, y, w, h = (float(v) for v in roi)
        if w < 4 or h < 4:
            logger.warning("CSRTTrackingProcessor: ROI %s too small, ignored", roi)
            return
        self._pending_roi = (x, y, w, h)

    def customize_processing(self, id: int) -> None:  # noqa: A002 - published name
        """F1 drop target, F2 re-acquire now, F3 gain up, F4 gain down."""
        if id == 1:
            self._tracker, self._ref_feat, self._box, self._vector = None, None, None, None
            logger.info("CSRTTrackingProcessor: target dropped")
        elif id == 2:
            self._force_search = True
        elif id == 3:
            self.steering.scale_gain(1.25)
        elif id == 4:
            self.steering.scale_gain(1 / 1.25)

    def getPreparedVector(self) -> Vector | None:
        """(vx, vy, t) towards the target, or None when there is no tracked target."""
        return self._vector

    # ---- state ----------------------------------------------------------------------------------
    @property
    def box(self) -> Box | None:
        """Tracked box (x, y, w, h) in frame pixels, None when lost or idle."""
        return self._box

    @property
    def lost(self) -> bool:
        """True while a target is selected but not currently tracked."""
        return self._ref_feat is not None and self._box is None

    # ---- internals ------------------------------------------------------------------------------
    def _sift_gray(self, gray: np.ndarray) -> tuple[np.ndarray, float]:
        sw = self._cfg["sift_width"]
        scale = sw / gray.shape[1] if 0 < sw < gray.shape[1] else 1.0
        if scale == 1.0:
            return gray, 1.0
        return cv2.resize(gray, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA), scale

    def _new_tracker(self, frame: np.ndarray, box: Box) -> None:
        params = cv2.TrackerCSRT_Params()
        for key, val in self._cfg["csrt"].items():
            setattr(params, key, val)
        self._tracker = cv2.TrackerCSRT_create(params)
        self._tracker.init(frame, tuple(int(round(v)) for v in box))
        self._box = box
        self._lost_frames = 0
        self._force_search = False

    def _start(self, frame: np.ndarray, gray: np.ndarray, roi: Box) -> None:
        fw, fh = self._frame_size
        x0, y0 = max(roi[0], 0.0), max(roi[1], 0.0)
        x1, y1 = min(roi[0] + roi[2], float(fw)), min(roi[1] + roi[3], float(fh))
        if x1 - x0 < 4 or y1 - y0 < 4:
            logger.warning("CSRTTrackingProcessor: ROI %s is outside the %dx%d frame, ignored", roi, fw, fh)
            return
        roi = (x0, y0, x1 - x0, y1 - y0)
        small, scale = self._sift_gray(gray)
        box = tuple(v * scale for v in roi)
        mask = np.zeros(small.shape, np.uint8)
        x, y, w, h = (int(round(v)) for v in box)
        mask[max(y, 0) : y + h, max(x, 0) : x + w] = 255
        self._ref_feat = sift_match.detect(self._sift, small, mask)
        self._ref_box = box  # type: ignore[assignment]
        self._ref_patch = _patch(gray, roi)
        self._recent_patch = self._ref_patch
        self._ref_height = roi[3]
        self._new_tracker(frame, roi)
        logger.info("CSRTTrackingProcessor: target %s selected, %d SIFT keypoints", roi, len(self._ref_feat))
        if len(self._ref_feat) < self.min_inliers:
            logger.warning("CSRTTrackingProcessor: few keypoints on the target, re-acquisition will be weak")

    def _update(self, frame: np.ndarray, gray: np.ndarray) -> None:
        ok, bb = self._tracker.update(frame)
        patch = _patch(gray, bb) if ok else None
        self.similarity = self._appearance(patch)
        if ok and self.similarity >= self.min_similarity:
            self._box = tuple(float(v) for v in bb)  # type: ignore[assignment]
            if self.similarity >= _ADAPT_ABOVE and patch is not None and self._recent_patch is not None:
                blend = (1 - _ADAPT_RATE) * self._recent_patch + _ADAPT_RATE * patch
                self._recent_patch = blend / max(float(np.linalg.norm(blend)), 1e-6)
        else:
            logger.info("CSRTTrackingProcessor: target lost (csrt ok=%s, similarity %.2f)", ok, self.similarity)
            self._box = None
            self._lost_frames = 0

    def _reacquire(self, frame: np.ndarray, gray: np.ndarray) -> None:
        self._force_search = False
        small, scale = self._sift_gray(gray)
        found = sift_match.match_homography(
            self._ref_feat, sift_match.detect(self._sift, small), self.ratio, self.min_inliers
        )
        if found is None:
            return
        corners = sift_match.project_box(found.homography, self._ref_box)
        if not cv2.isContourConvex(corners.astype(np.float32)):
            return
        x0, y0 = corners.min(axis=0) / scale
        x1, y1 = corners.max(axis=0) / scale
        box = (float(x0), float(y0), float(x1 - x0), float(y1 - y0))
        area_ratio = (box[2] * box[3]) * scale**2 / (self._ref_box[2] * self._ref_box[3])
        sim = self._appearance(_patch(gray, box))
        if not 0.25 < area_ratio < 4.0 or sim < self.min_similarity:
            return
        self._new_tracker(frame, box)
        self.similarity = sim
        logger.info("CSRTTrackingProcessor: re-acquired (%d inliers, similarity %.2f)", found.inliers, sim)
        if self.tmMgr is not None:
            self.tmMgr.save(frame, event="reacquired", inliers=found.inliers, similarity=round(sim, 3))

    def _appearance(self, patch: np.ndarray | None) -> float:
        """Similarity of ``patch`` to the target: the better of the selection and the adapted template."""
        return max(_similarity(patch, self._ref_patch), _similarity(patch, self._recent_patch))

    def _draw(self, frame: np.ndarray) -> None:
        if self._box is not None:
            draw_target(frame, self._box, self._vector, (0, 255, 0), f"{self.similarity:.2f}")
        elif self._ref_feat is not None:
            cv2.putText(frame, "LOST - searching", (8, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (0, 0, 255), 2)
