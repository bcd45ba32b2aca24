"""SIFT homography position hold: keeps a downward-looking vehicle over a reference spot without GPS."""

from __future__ import annotations

import logging
import math
from typing import Any

import cv2
import numpy as np

from processors import sift_match
from processors.frame_telemetry import FrameTelemetry, frame_time_s
from processors.steering import Vector, draw_vector, velocity_toward

logger = logging.getLogger(__name__)

_MODES: dict[str, dict[str, Any]] = {
    # 320-px-wide work frame, capped SIFT, reference descriptors computed once, 5 estimates/s
    "fast": {"work_width": 320, "sift_features": 800, "interval_s": 0.2, "reuse_reference": True},
    # the paper: full frame, unlimited SIFT, both images described again, every frame
    "paper": {"work_width": 0, "sift_features": 0, "interval_s": 0.0, "reuse_reference": False},
}


class SIFTPositionHold:
    """Hold position over a ground spot by matching the current view to a stored reference view.

    F1 stores the next frame as the reference (the spot is the frame centre: hold here);
    ``catch_cmd(roi)`` does the same with the spot at the ROI centre (go and hold over that spot).
    Then, at its own rate (``interval_s`` of the frames' capture time, ``tmMgr.snapshot().frame_t_ns``, so a
    replay at any speed estimates on the same frames; frames in between are skipped, each estimate compares
    the newest frame with the reference, so skipped frames change nothing), it fits a homography
    reference -> current, maps the spot into the current frame and converts its offset from the
    frame centre into metres: ground metres per pixel = 2 * altitude * tan(hfov / 2) / width,
    altitude = ``tmMgr.snapshot().rel_alt_m`` (``altitude_m`` when unknown). With
    ``compensate_tilt`` the apparent shift caused by roll/pitch (telemetry) is removed.

    Assumes a nadir camera aligned with the body: image up = forward, image right = right.

    Vector: body-frame velocity (vx forward, vy right, m/s) = ``gain`` x offset to the reference
    position, scaled so neither component exceeds ``max_speed``; zero inside ``dead_band_m``;
    ``t`` = ``vector_t`` s. ``getPreparedVector`` returns each fresh estimate once and None when
    there is no reference, no new estimate since the last call, or the match failed.

    Operator buttons:
        F1: store the reference (hold here).
        F2: clear the reference (stop holding).
        F3: gain x 1.25.
        F4: gain / 1.25.

    Args:
        mode: "fast" or "paper" (see the module's ``_MODES``).
        hfov_deg: horizontal field of view of the camera (Raspberry Pi Camera v2: 62.2).
        altitude_m: altitude used when telemetry has none.
        gain: m/s per metre of offset.
        max_speed, dead_band_m, vector_t: vector limits.
        min_inliers, ratio: SIFT matching thresholds.
        compensate_tilt: remove the image shift due to roll/pitch (telemetry degrees).
        work_width, sift_features, interval_s: override the mode's values.
    """

    def __init__(
        self,
        mode: str = "fast",
        hfov_deg: float = 62.2,
        altitude_m: float = 10.0,
        gain: float = 0.5,
        max_speed: float = 1.0,
        dead_band_m: float = 0.2,
        vector_t: float = 1.0,
        min_inliers: int = 12,
        ratio: float = 0.75,
        compensate_tilt: bool = True,
        work_width: int | None = None,
        sift_features: int | None = None,
        interval_s: float | None = None,
    ) -> None:
        if mode not in _MODES:
            raise ValueError(f"mode must be one of {sorted(_MODES)}, got {mode!r}")
        cfg = dict(_MODES[mode])
        overrides = {"work_width": work_width, "sift_features": sift_features, "interval_s": interval_s}
        cfg.update({k: v for k, v in overrides.items() if v is not None})
        self.tmMgr: FrameTelemetry | None = None
        self.mode = mode
        self.hfov_deg = hfov_deg
        self.altitude_m = altitude_m
        self.gain = gain
        self.max_speed = min(abs(max_speed), 1.0)
        self.dead_band_m = dead_band_m
        self.vector_t = min(max(vector_t, 0.05), 2.0)
        self.min_inliers = min_inliers
        self.ratio = ratio
        self.compensate_tilt = compensate_tilt
        self._cfg = cfg
        self._sift = sift_match.make_sift(cfg["sift_features"])
        self._pending_spot: tuple[float, float] | None = None  # frame pixels, or (-1, -1) = centre
        self._ref_gray: np.ndarray | None = None
        self._ref_feat: sift_match.Features | None = None
        self._ref_spot = (0.0, 0.0)  # work pixels
        self._ref_tilt = (0.0, 0.0)  # (roll, pitch) degrees at reference time
        self._last_estimate = -math.inf
        self._vector: Vector | None = None
        self._fresh = False
        self._overlay: tuple[np.ndarray, tuple[float, float]] | None = None
        self.offset_m: tuple[float, float] | None = None
        """Last estimate: (forward, right) metres from the vehicle to the reference position."""
        self.inliers = 0
        """RANSAC inliers of the last estimate."""

    # ---- contract -------------------------------------------------------------------------------
    def photo_processing(self, frame: np.ndarray) -> None:
        """Store the reference or, when due, estimate the offset; draw the overlay in place.

        Other frames (no reference, or between estimates) are only drawn on: they are not converted or scaled.
        """
        scale = self._scale(frame.shape[1])
        if self._pending_spot is not None:
            work = self._work(frame, scale)
            sx, sy = self._pending_spot
            spot = (work.shape[1] / 2.0, work.shape[0] / 2.0) if sx < 0 else (sx * scale, sy * scale)
            self._store_reference(work, spot, at_centre=sx < 0)
            self._pending_spot = None
        elif (self._ref_gray is not None and self._ref_feat is not None
              and frame_time_s(self.tmMgr) - self._last_estimate >= self._cfg["interval_s"]):
            self._last_estimate = frame_time_s(self.tmMgr)
            self._estimate(self._work(frame, scale), frame, self._ref_gray, self._ref_feat)
        self._draw(frame, scale)

    def catch_cmd(self, roi: tuple[int, int, int, int]) -> None:
        """Store the reference from the next frame, the spot to hold over being the ROI centre."""
        x, y, w, h = roi
        self._pending_spot = (x + w / 2.0, y + h / 2.0)

    def customize_processing(self, id: int) -> None:  # noqa: A002 - published name
        """F1 store reference, F2 clear it, F3 gain up, F4 gain down."""
        if id == 1:
            self._pending_spot = (-1.0, -1.0)
        elif id == 2:
            self._ref_gray, self._ref_feat, self._vector, self._overlay, self.offset_m = (None,) * 5
            logger.info("SIFTPositionHold: reference cleared")
        elif id in (3, 4):
            self.gain = float(np.clip(self.gain * (1.25 if id == 3 else 0.8), 0.05, 5.0))
            logger.info("SIFTPositionHold: gain now %.2f", self.gain)

    def getPreparedVector(self) -> Vector | None:
        """The vector of the newest estimate, once; None until the next estimate."""
        fresh, self._fresh = self._fresh, False
        return self._vector if fresh else None

    # ---- internals ------------------------------------------------------------------------------
    def _scale(self, width: int) -> float:
        """Work pixels per frame pixel: down to ``work_width``, never up."""
        work_width = self._cfg["work_width"]
        return work_width / width if 0 < work_width < width else 1.0

    def _work(self, frame: np.ndarray, scale: float) -> np.ndarray:
        gray = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        if scale == 1.0:
            return gray
        return cv2.resize(gray, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)

    def _telemetry(self) -> tuple[float, float, float]:
        """(altitude m, roll deg, pitch deg); fallbacks where telemetry is missing."""
        if self.tmMgr is None:
            return self.altitude_m, 0.0, 0.0
        snap = self.tmMgr.snapshot()
        alt, roll, pitch = snap.rel_alt_m, snap.roll_deg or 0.0, snap.pitch_deg or 0.0
        return (alt if alt is not None and alt > 0.3 else self.altitude_m), roll, pitch

    def _store_reference(self, work: np.ndarray, spot: tuple[float, float], at_centre: bool) -> None:
        self._ref_gray = work
        self._ref_feat = sift_match.detect(self._sift, work)
        self._ref_spot = spot
        # "hold here": the vehicle's own position, which a tilted camera does not see at the centre
        self._ref_tilt = self._telemetry()[1:] if at_centre else (0.0, 0.0)
        self._last_estimate = -math.inf
        logger.info("SIFTPositionHold: reference stored, %d SIFT keypoints", len(self._ref_feat))

    def _estimate(self, work: np.ndarray, frame: np.ndarray, ref_gray: np.ndarray, ref_feat: sift_match.Features
                  ) -> None:
        ref = ref_feat if self._cfg["reuse_reference"] else sift_match.detect(self._sift, ref_gray)
        found = sift_match.match_homography(ref, sift_match.detect(self._sift, work), self.ratio, self.min_inliers)
        det = np.linalg.det(found.homography[:2, :2]) if found is not None else 0.0
        if found is None or not 0.4 < det < 2.5:
            logger.info("SIFTPositionHold: no reliable match (det %.2f)", det)
            self.offset_m, self.inliers, self._overlay, self._vector = None, 0, None, None
            return
        self.inliers = found.inliers
        spot = cv2.perspectiveTransform(np.array([[self._ref_spot]], np.float32), found.homography)[0, 0]
        alt, roll, pitch = self._telemetry()
        h, w = work.shape
        m_per_px = 2.0 * alt * math.tan(math.radians(self.hfov_deg) / 2.0) / w
        forward = -(float(spot[1]) - h / 2.0) * m_per_px
        right = (float(spot[0]) - w / 2.0) * m_per_px
        if self.compensate_tilt:
            # roll right shows the ground under the vehicle right of centre, pitch up shows it below
            right += alt * (math.tan(math.radians(self._ref_tilt[0])) - math.tan(math.radians(roll)))
            forward += alt * (math.tan(math.radians(pitch)) - math.tan(math.radians(self._ref_tilt[1])))
        self.offset_m = (forward, right)
        self._vector = velocity_toward(forward, right, self.gain, self.max_speed, self.dead_band_m, self.vector_t)
        self._fresh = True
        self._overlay = (found.homography, (float(spot[0]), float(spot[1])))
        if self.tmMgr is not None:
            self.tmMgr.save(
                frame,
                hold_forward_m=round(forward, 3),
                hold_right_m=round(right, 3),
                hold_inliers=found.inliers,
            )

    def _draw(self, frame: np.ndarray, scale: float) -> None:
        if self._ref_gray is None:
            return
        if self._overlay is None or self.offset_m is None:
            cv2.putText(frame, "HOLD: no match", (8, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (0, 0, 255), 2)
            return
        hom, spot = self._overlay
        h, w = self._ref_gray.shape
        outline = sift_match.project_box(hom, (0.0, 0.0, float(w), float(h))) / scale
        cv2.polylines(frame, [outline.astype(np.int32)], True, (255, 200, 0), 1)
        cv2.circle(frame, (int(spot[0] / scale), int(spot[1] / scale)), 6, (255, 200, 0), 2)
        fwd, right = self.offset_m
        cv2.putText(
            frame,
            f"fwd {fwd:+.2f} m  right {right:+.2f} m",
            (8, 20),
            cv2.FONT_HERSHEY_SIMPLEX,
            0.6,
            (255, 200, 0),
            2,
        )
        draw_vector(frame, self._vector)
