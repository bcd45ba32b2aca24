"""Pinhole-camera geometry for the simulated camera: vehicle pose -> ground-plane homography.

Frames: the world is NED (north, east, down; the ground is the plane ``d = 0``), the body is
FRD (forward, right, down) rotated from NED by yaw, pitch, roll (ZYX), and the camera is the
usual computer-vision frame (x right, y down in the image, z along the optical axis).
The camera is fixed to the body, tilted down from the body's forward axis by ``tilt_deg``:
90 (the default) looks straight down with the top of the image towards the nose, 0 looks ahead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from uav_values.camera import rotation_body_camera

DEFAULT_ALTITUDE_M = 10.0
"""Altitude of the pose used before the vehicle reports one."""

MIN_CAMERA_HEIGHT_M = 0.2
"""Camera height above the ground when the vehicle sits on it (``d = 0``): the camera is above the skids."""


@dataclass(frozen=True, slots=True)
class Pose:
    """Vehicle position (m, NED; ``d`` is negative above the ground) and attitude (degrees)."""

    n: float = 0.0
    e: float = 0.0
    d: float = -DEFAULT_ALTITUDE_M
    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0

    @classmethod
    def from_mapping(cls, values: dict[str, Any]) -> Pose:
        """From a truth datagram ``{"n", "e", "d", "roll", "pitch", "yaw", ...}``; extra keys are ignored."""
        return cls(**{name: float(values[name]) for name in cls.__slots__ if name in values})


@dataclass(frozen=True, slots=True)
class PinholeCamera:
    """An ideal camera: image size, horizontal field of view and its mounting tilt."""

    width: int = 640
    height: int = 480
    hfov_deg: float = 62.0
    tilt_deg: float = 90.0

    @property
    def focal_px(self) -> float:
        """Focal length in pixels (square pixels)."""
        return (self.width / 2) / math.tan(math.radians(self.hfov_deg) / 2)

    @property
    def intrinsics(self) -> np.ndarray:
        """The 3x3 matrix K."""
        f = self.focal_px
        return np.array([[f, 0.0, self.width / 2], [0.0, f, self.height / 2], [0.0, 0.0, 1.0]])


def rotation_world_body(roll_deg: float, pitch_deg: float, yaw_deg: float) -> np.ndarray:
    """Body (FRD) axes expressed in NED: ``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``."""
    r, p, y = (math.radians(a) for a in (roll_deg, pitch_deg, yaw_deg))
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    rotation: np.ndarray = rz @ ry @ rx
    return rotation


def rotation_world_camera(pose: Pose, camera: PinholeCamera) -> np.ndarray:
    """Camera axes expressed in NED."""
    rotation: np.ndarray = rotation_world_body(pose.roll, pose.pitch, pose.yaw) @ rotation_body_camera(camera.tilt_deg)
    return rotation


def camera_centre(pose: Pose) -> np.ndarray:
    """The camera's NED position: the vehicle's, never lower than ``MIN_CAMERA_HEIGHT_M`` above the ground."""
    return np.array([pose.n, pose.e, min(pose.d, -MIN_CAMERA_HEIGHT_M)])


def ground_to_image(pose: Pose, camera: PinholeCamera) -> np.ndarray:
    """The homography taking a ground point ``(n, e, 1)`` to homogeneous image pixels."""
    r_cw = rotation_world_camera(pose, camera).T
    t = -r_cw @ camera_centre(pose)
    homography: np.ndarray = camera.intrinsics @ np.column_stack([r_cw[:, 0], r_cw[:, 1], t])
    return homography


def project_ground_point(n: float, e: float, pose: Pose, camera: PinholeCamera) -> tuple[float, float] | None:
    """Pixel ``(u, v)`` where the ground point ``(n, e)`` appears, or None if it is behind the camera.

    ``u`` grows to the right, ``v`` downwards; the point may fall outside the image.
    """
    x, y, w = ground_to_image(pose, camera) @ np.array([n, e, 1.0])
    if w <= 1e-9:
        return None
    return float(x / w), float(y / w)


def ray_down_coefficients(pose: Pose, camera: PinholeCamera) -> np.ndarray:
    """(a, b, c) such that the ray through pixel (u, v) points down by ``a*u + b*v + c`` (unnormalized).

    Where this is <= 0 the pixel sees the sky, not the ground.
    """
    coefficients: np.ndarray = rotation_world_camera(pose, camera)[2] @ np.linalg.inv(camera.intrinsics)
    return coefficients


def ground_sample_distance(pose: Pose, camera: PinholeCamera, pixel: tuple[float, float]) -> float | None:
    """Metres of ground one pixel spans at ``pixel`` (None if that pixel sees the sky)."""
    direction = rotation_world_camera(pose, camera) @ np.linalg.inv(camera.intrinsics) @ np.array([*pixel, 1.0])
    if direction[2] <= 1e-9:
        return None
    distance = -float(camera_centre(pose)[2] / direction[2]) * float(np.linalg.norm(direction))
    return distance / camera.focal_px
