"""MAVLink's attitude quaternions (``w, x, y, z``) to and from ZYX Euler angles (roll, pitch, yaw; radians)."""

from __future__ import annotations

import math
from collections.abc import Sequence


def quaternion(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    """``(w, x, y, z)`` of the ZYX Euler angles (radians)."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy)


def euler(q: Sequence[float]) -> tuple[float, float, float]:
    """ZYX Euler angles (radians: roll, pitch, yaw) of the quaternion ``(w, x, y, z)``.

    Raises:
        ValueError: not four numbers.
    """
    w, x, y, z = (float(c) for c in q)
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return roll, pitch, yaw
