"""LANDING_TARGET as each autopilot takes it, from a landing target seen in one camera frame.

What each autopilot does with the message (read in their sources, PX4 v1.16 and ArduPilot 4.x):

* **ArduPilot** (``AC_PrecLand_Companion``, ``PLND_TYPE=1``): angles in ``MAV_FRAME_BODY_FRD`` (12) or
  ``LOCAL_FRD``; other frames are dropped ("Plnd: Frame not supported"). Without ``position_valid`` it
  builds the line of sight as a camera looking down would see it, ``(-tan(angle_y), tan(angle_x), 1)`` in the
  body frame (forward, right, down), and rotates it by its own attitude history at the capture time.
  ``distance`` replaces its rangefinder when > 0. ``time_usec`` goes through its jitter correction, which
  learns the offset of whatever clock the sender uses.
* **PX4** (``mavlink_receiver.cpp``): only ``position_valid = 1`` in ``MAV_FRAME_LOCAL_NED`` (1) becomes a
  target pose, ``x, y, z`` the pad's position in the local frame (not relative to the vehicle); angles alone
  go to the IR-LOCK path. ``time_usec`` goes through its TIMESYNC offset to the sender, which MAVSDK answers
  in the autopilot's own time: so the capture time is sent in the autopilot's clock (µs since its boot).

So the platform hands the controller the direction in the camera frame, the mounting (from the camera model),
and the attitude and position at the frame's capture; this module does the geometry, nothing else.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from controllers.autopilots import Autopilot
from controllers.errors import ControllerError

MAV_FRAME_LOCAL_NED = 1
MAV_FRAME_BODY_FRD = 12
LANDING_TARGET_TYPE_VISION_FIDUCIAL = 2

Vector3 = tuple[float, float, float]


class LandingTargetError(ControllerError):
    """A landing target this autopilot cannot be given (what is missing is in the message)."""


@dataclass(frozen=True)
class LandingTargetFix:
    """A landing target as the platform hands it to the controller.

    Args:
        capture_mono_ns: the frame's capture time, ``time.monotonic_ns()``.
        direction_camera: unit vector from the camera to the pad, camera frame (x right, y down, z ahead).
        distance_m: camera to pad in metres, or None.
        rotation_body_camera: the camera's axes in the body frame (columns x, y, z), from the camera model.
        camera_offset_frd: the camera's position from the vehicle's centre, body frame (forward, right, down), m.
        attitude_deg: roll, pitch, yaw (degrees) at the capture, or None.
        position_ned: the vehicle's local position (north, east, down; m) at the capture, or None.
    """

    capture_mono_ns: int
    direction_camera: Vector3
    distance_m: float | None
    rotation_body_camera: np.ndarray
    camera_offset_frd: Vector3 = (0.0, 0.0, 0.0)
    attitude_deg: Vector3 | None = None
    position_ned: Vector3 | None = None

    @property
    def direction_body(self) -> np.ndarray:
        """The unit direction to the pad in the body frame (forward, right, down)."""
        return np.asarray(self.rotation_body_camera, float) @ np.asarray(self.direction_camera, float)


def rotation_ned_body(roll_deg: float, pitch_deg: float, yaw_deg: float) -> np.ndarray:
    """Body (FRD) axes in NED: ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``."""
    r, p, y = (math.radians(a) for a in (roll_deg, pitch_deg, yaw_deg))
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _common(time_usec: int, distance_m: float | None) -> dict[str, Any]:
    return {"time_usec": int(time_usec), "target_num": 0, "distance": float(distance_m or 0.0), "size_x": 0.0,
            "size_y": 0.0, "type": LANDING_TARGET_TYPE_VISION_FIDUCIAL, "q": [1.0, 0.0, 0.0, 0.0]}


def ardupilot_fields(fix: LandingTargetFix, time_usec: int) -> dict[str, Any]:
    """LANDING_TARGET fields for ArduPilot: the body-frame direction as a downward camera's angles, BODY_FRD.

    Raises:
        LandingTargetError: the pad is not below the vehicle's body plane (a downward line of sight can't say it).
    """
    forward, right, down = fix.direction_body
    if down <= 1e-6:
        raise LandingTargetError("landing target: the pad is not below the vehicle (ArduPilot takes a line of "
                                 "sight below it): not sent")
    return {**_common(time_usec, fix.distance_m), "frame": MAV_FRAME_BODY_FRD, "angle_x": math.atan2(right, down),
            "angle_y": math.atan2(-forward, down), "x": 0.0, "y": 0.0, "z": 0.0, "position_valid": 0}


def px4_fields(fix: LandingTargetFix, time_usec: int) -> dict[str, Any]:
    """LANDING_TARGET fields for PX4: the pad's local NED position, ``position_valid = 1``.

    The pad = the vehicle's position + R(attitude) (camera offset + distance x body direction).

    Raises:
        LandingTargetError: no distance, attitude or position at the capture (PX4 takes a position only).
    """
    missing = [name for name, value in (("distance", fix.distance_m), ("attitude", fix.attitude_deg),
                                        ("position", fix.position_ned)) if value is None]
    if missing:
        raise LandingTargetError(f"landing target: PX4 takes the pad's position, which needs the "
                                 f"{' and '.join(missing)} at the capture: not sent")
    assert fix.distance_m is not None and fix.attitude_deg is not None and fix.position_ned is not None
    body = np.asarray(fix.camera_offset_frd, float) + fix.distance_m * fix.direction_body
    north, east, down = np.asarray(fix.position_ned, float) + rotation_ned_body(*fix.attitude_deg) @ body
    forward, right, below = fix.direction_body
    angles = (math.atan2(right, below), math.atan2(-forward, below)) if below > 1e-6 else (0.0, 0.0)
    return {**_common(time_usec, fix.distance_m), "frame": MAV_FRAME_LOCAL_NED, "angle_x": angles[0],
            "angle_y": angles[1], "x": float(north), "y": float(east), "z": float(down), "position_valid": 1}


def landing_target_fields(autopilot: Autopilot, fix: LandingTargetFix, time_usec: int) -> dict[str, Any]:
    """The LANDING_TARGET fields ``autopilot`` (PX4 or ArduPilot) takes for ``fix``.

    Raises:
        LandingTargetError: an unknown autopilot, a fix it cannot be given, or fields that would not be finite.
    """
    if autopilot not in (Autopilot.ARDUPILOT, Autopilot.PX4):
        raise LandingTargetError(f"landing target: unknown autopilot {autopilot.value!r} (PX4 and ArduPilot take "
                                 "LANDING_TARGET differently): not sent")
    fields = ardupilot_fields(fix, time_usec) if autopilot is Autopilot.ARDUPILOT else px4_fields(fix, time_usec)
    broken = sorted(name for name, value in fields.items() if isinstance(value, float) and not math.isfinite(value))
    if broken:  # MAVLink would carry it; MAVSDK's JSON parser is no place to find out
        raise LandingTargetError(f"landing target: {', '.join(broken)} not finite (direction {fix.direction_camera}, "
                                 f"{fix.distance_m} m, attitude {fix.attitude_deg}, position {fix.position_ned}): "
                                 "not sent")
    return fields
