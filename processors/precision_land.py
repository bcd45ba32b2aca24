"""Precision landing on an ArUco / AprilTag marker: the pad's pose from its corners and the camera model."""

from __future__ import annotations

import logging
import math
import re
from typing import TYPE_CHECKING

import cv2
import numpy as np

from processors import markers
from uav_values.landing_target import LandingTarget

if TYPE_CHECKING:
    from processors.frame_telemetry import FrameTelemetry
    from uav_values.camera import CameraModel

logger = logging.getLogger(__name__)

EDGE_MARGIN_PX = 4.0
"""A marker with a corner this close to the frame's border may be cut off: no target from it. (ArUco itself finds
no marker within 3 px of the border; one lost within a marker's width of it is reported as partly out of frame.)"""

MIN_CHECK_HEIGHT_M = 2.0
"""Below this height above home the size check is skipped (home's level and the pad's may differ by a metre)."""

MAX_REPROJECTION_PX = 3.0
"""A pose whose corners reproject further than this (RMS) from the detected ones is not a flat square."""

GREEN, RED, YELLOW = (0, 200, 0), (0, 0, 230), (0, 220, 255)

_NUMBER = re.compile(r"\d+(?:\.\d+)?")


class PrecisionLand:
    """Finds the landing pad's marker and returns where it is as the landing target.

    Each frame: detect the markers of ``dictionary``; if exactly one has ``marker_id``, is wholly inside the frame,
    and the camera model (``tmMgr.camera()``) is known, its pose comes from its four corners with ``solvePnP``
    (``SOLVEPNP_IPPE_SQUARE``, ``marker_size_m`` the printed black square's side) and ``getLandingTarget()``
    returns the direction to its centre (camera frame) and the distance. Otherwise ``getLandingTarget()`` is
    None and ``status`` says why: ``no camera model``, ``marker 3 not in view``, ``2 markers with id 3``,
    ``marker 3 partly out of frame``, ``size check``: the distance the size gives against the height above home
    the telemetry gives (a wrong ``marker_size_m`` scales every distance by the same factor; the status says
    which size would fit). The size check needs ``rel_alt_m`` and is skipped below ``MIN_CHECK_HEIGHT_M``;
    ``size_tolerance=None`` turns it off (a pad not at home's level).

    It returns no vector: the autopilot's own precision-landing controller flies the descent.

    Operator buttons:
        F1: next marker id (the next one in view, else id + 1).
        F2: previous marker id.
        F3: pause / resume the landing target (paused: None every frame).
        F4: log the marker's pose (distance, angles, height check).

    Args:
        dictionary: OpenCV's dictionary name, ``4x4_50`` ... ``aruco_original``, ``apriltag_36h11`` ...
        marker_id: the pad's marker id in that dictionary.
        marker_size_m: the side of the marker's black square, metres.
        size_tolerance: the largest accepted |distance-given height / telemetry height - 1|; None: no check.
    """

    def __init__(self, dictionary: str = "4x4_50", marker_id: int = 0, marker_size_m: float = 0.5,
                 size_tolerance: float | None = 0.25) -> None:
        if not 0.01 <= marker_size_m <= 100:
            raise ValueError(f"marker_size_m {marker_size_m:g} must be 0.01..100 metres (the black square's side)")
        if marker_id < 0:
            raise ValueError(f"marker_id {marker_id} must be >= 0")
        self.tmMgr: FrameTelemetry | None = None
        self.dictionary = markers.dictionary_name(dictionary)
        self.marker_id = marker_id
        self.marker_size_m = marker_size_m
        self.size_tolerance = size_tolerance
        self._detector = markers.make_detector(self.dictionary)
        self.paused = False
        self.status = "no frame yet"
        """What the last frame gave: ``marker 0 at 6.42 m`` or why there is no target."""
        self.seen: list[tuple[int, np.ndarray]] = []
        """Every marker of the dictionary in the last frame: (id, corners)."""
        self.pose: markers.MarkerPose | None = None
        """The pad marker's pose in the last frame, when it had one (also when the size check failed)."""
        self.box: tuple[int, int, int, int] | None = None
        self._target: LandingTarget | None = None
        self._last_corners: np.ndarray | None = None
        """The pad's corners when it was last seen alone (to tell that it left the frame, and where)."""

    # ---- contract -------------------------------------------------------------------------------
    def photo_processing(self, frame: np.ndarray) -> None:
        """Find the pad, set the target (or the reason there is none), draw the overlay in place."""
        self._target, self.pose, self.box = None, None, None
        self.seen = markers.detect(self._detector, frame)
        self._set_status(self._locate(frame))
        self._draw(frame)

    def customize_processing(self, id: int) -> None:  # noqa: A002 - the published name
        if id in (1, 2):
            self._step_id(1 if id == 1 else -1)
            self._last_corners = None
        elif id == 3:
            self.paused = not self.paused
            logger.info("PrecisionLand: landing target %s", "paused" if self.paused else "resumed")
        elif id == 4:
            logger.info("PrecisionLand: %s", self.describe_pose())

    def getLandingTarget(self) -> LandingTarget | None:  # noqa: N802 - the published naming
        """The pad seen in the frame just processed, or None (see ``status``)."""
        return None if self.paused else self._target

    # ---- the pad --------------------------------------------------------------------------------
    def _locate(self, frame: np.ndarray) -> str:
        found = [corners for marker_id, corners in self.seen if marker_id == self.marker_id]
        height, width = frame.shape[:2]
        if found:
            self._last_corners = found[0] if len(found) == 1 else None
        else:
            last = self._last_corners
            edge = None if last is None else markers.nearest_edge(last, width, height)
            if edge is not None:
                return f"marker {self.marker_id} out of frame at the {edge} edge (last seen there): no target"
            others = sorted({marker_id for marker_id, _ in self.seen})
            return f"marker {self.marker_id} not in view" + (f" (in view: {others})" if others else "")
        if len(found) > 1:
            return f"{len(found)} markers with id {self.marker_id}: which is the pad? no target"
        corners = found[0]
        x, y = corners.min(axis=0)
        w, h = corners.max(axis=0) - (x, y)
        self.box = round(x), round(y), max(1, round(w)), max(1, round(h))
        if markers.distance_to_edge(corners, width, height) < EDGE_MARGIN_PX:
            return f"marker {self.marker_id} partly out of frame: no target"
        camera = self.tmMgr.camera() if self.tmMgr is not None else None
        if camera is None:
            return "no camera model (calibrate, or give the camera's hfov): no target"
        pose = markers.marker_pose(corners, self.marker_size_m, camera.matrix, camera.distortion_array)
        if pose is None or pose.reprojection_px > MAX_REPROJECTION_PX:
            return f"marker {self.marker_id}: no consistent pose from its corners: no target"
        self.pose = pose
        mismatch = self._size_check(pose, camera)
        if mismatch:
            return mismatch
        seq = self.tmMgr.snapshot().frame_seq if self.tmMgr is not None else None
        self._target = LandingTarget(tuple(pose.tvec), pose.distance_m, seq)
        return f"marker {self.marker_id} at {pose.distance_m:.2f} m"

    def _size_check(self, pose: markers.MarkerPose, camera: CameraModel) -> str | None:
        """Why the distance does not fit the telemetry's height above home, or None when it fits (or can't say)."""
        if self.tmMgr is None:
            return None
        snapshot = self.tmMgr.snapshot()
        height = snapshot.rel_alt_m
        if self.size_tolerance is None or height is None or height < MIN_CHECK_HEIGHT_M:
            return None
        roll, pitch = (math.radians(angle or 0.0) for angle in (snapshot.roll_deg, snapshot.pitch_deg))
        forward, right, down = camera.ray_in_body(pose.tvec)
        # NED down of a body-frame vector: the third row of Rz(yaw) Ry(pitch) Rx(roll).
        drop = -math.sin(pitch) * forward + math.cos(pitch) * (math.sin(roll) * right + math.cos(roll) * down)
        if drop <= 0:
            return None
        ratio = drop / height
        if abs(ratio - 1) <= self.size_tolerance:
            return None
        return (f"size check: marker {self.marker_id} gives {drop:.1f} m below the camera but the vehicle is "
                f"{height:.1f} m above home; is marker_size_m {self.marker_size_m:g} right "
                f"({self.marker_size_m / ratio:.2f} m would fit)? no target")

    def _set_status(self, status: str) -> None:
        """Set ``status``; log it when it says something new (a new distance alone is not news)."""
        changed = _NUMBER.sub("#", status) != _NUMBER.sub("#", self.status)
        self.status = status
        if changed:
            logger.info("PrecisionLand: %s", status)

    def _step_id(self, step: int) -> None:
        in_view = sorted({marker_id for marker_id, _ in self.seen} - {self.marker_id})
        later = [i for i in in_view if (i - self.marker_id) * step > 0]
        if later:
            self.marker_id = later[0] if step > 0 else later[-1]
        elif in_view:
            self.marker_id = in_view[0] if step > 0 else in_view[-1]
        else:
            self.marker_id = max(0, self.marker_id + step)
        logger.info("PrecisionLand: landing on marker %d", self.marker_id)

    def describe_pose(self) -> str:
        """The pad's pose in one line (F4), or the status when there is none."""
        if self.pose is None:
            return self.status
        x, y, z = self.pose.tvec
        return (f"marker {self.marker_id}: {self.pose.distance_m:.2f} m, {math.degrees(math.atan2(x, z)):+.1f} deg "
                f"right, {math.degrees(math.atan2(y, z)):+.1f} deg down, reprojection {self.pose.reprojection_px:.2f}"
                f" px; {self.status}")

    # ---- overlay --------------------------------------------------------------------------------
    def _draw(self, frame: np.ndarray) -> None:
        for marker_id, corners in self.seen:
            pad = marker_id == self.marker_id
            colour = (GREEN if self._target is not None else YELLOW) if pad else RED
            cv2.polylines(frame, [corners.round().astype(np.int32)], True, colour, 2 if pad else 1)
            label = f"id {marker_id}"
            if pad and self.pose is not None:
                label += f"  {self.pose.distance_m:.2f} m"
            x, y = corners.min(axis=0)
            cv2.putText(frame, label, (int(x), max(12, int(y) - 4)), cv2.FONT_HERSHEY_SIMPLEX, 0.45, colour, 1,
                        cv2.LINE_AA)
        if self._target is not None and self.tmMgr is not None and (camera := self.tmMgr.camera()) is not None:
            centre = camera.ray_to_pixel(np.array(self._target.direction))
            if centre is not None:
                cv2.drawMarker(frame, (round(centre[0]), round(centre[1])), GREEN, cv2.MARKER_CROSS, 14, 2)
        text = ("paused: " if self.paused else "") + self.status
        cv2.putText(frame, text[:70], (6, frame.shape[0] - 8), cv2.FONT_HERSHEY_SIMPLEX, 0.4,
                    GREEN if self._target is not None else YELLOW, 1, cv2.LINE_AA)
