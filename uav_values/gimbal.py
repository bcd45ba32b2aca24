"""The gimbal pointing: the contract's third optional output (``getGimbalPointing() -> GimbalPointing | None``).

A processor that wants the camera to look somewhere else returns, for the frame just processed, either angular
**rates** (degrees per second: keep a target centred by turning towards it) or **angles** (degrees: look there).
Pitch is positive up (MAVLink's gimbal convention: -90 looks straight down), yaw positive to the right and, as an
angle, relative to the vehicle's nose. The platform sends it through MAVLink's gimbal protocol v2 while the operator
has autonomy on, the frame is fresh and the link alive, and stops the gimbal and releases control on every stop.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real
from typing import Literal

RATE: Literal["rate"] = "rate"
ANGLE: Literal["angle"] = "angle"

MAX_RATE_DEG_S = 180.0
"""The fastest turn a :class:`GimbalPointing` may ask for, each axis (consumer gimbals slew at 90-200 deg/s)."""

PITCH_RANGE_DEG = (-90.0, 90.0)
"""Pitch angles a :class:`GimbalPointing` may ask for (-90: straight down, 0: level, +90: straight up)."""

YAW_RANGE_DEG = (-180.0, 180.0)
"""Yaw angles a :class:`GimbalPointing` may ask for, relative to the vehicle's nose (positive right)."""


@dataclass(frozen=True, slots=True)
class GimbalPointing:
    """Where the camera should turn, as asked after one frame. Build it with :meth:`rates` or :meth:`angles`.

    Args:
        mode: :data:`RATE` (``pitch``/``yaw`` in deg/s) or :data:`ANGLE` (degrees).
        pitch: positive up.
        yaw: positive right; as an angle, relative to the vehicle's nose.

    Raises:
        ValueError: a mode that is neither, a value that is not a finite real number, or out of range
            (rates within +-:data:`MAX_RATE_DEG_S`; angles within :data:`PITCH_RANGE_DEG` / :data:`YAW_RANGE_DEG`).
    """

    mode: Literal["rate", "angle"]
    pitch: float
    yaw: float

    def __post_init__(self) -> None:
        if self.mode not in (RATE, ANGLE):
            raise ValueError(f"gimbal pointing mode {self.mode!r} must be {RATE!r} or {ANGLE!r}")
        unit = "deg/s" if self.mode == RATE else "deg"
        for axis in ("pitch", "yaw"):
            value = getattr(self, axis)
            if not isinstance(value, Real) or isinstance(value, bool) or not math.isfinite(value):
                raise ValueError(f"gimbal {self.mode} {axis}={value!r:.40} must be a finite number ({unit})")
            low, high = ((-MAX_RATE_DEG_S, MAX_RATE_DEG_S) if self.mode == RATE else
                         PITCH_RANGE_DEG if axis == "pitch" else YAW_RANGE_DEG)
            if not low <= float(value) <= high:
                raise ValueError(f"gimbal {self.mode} {axis}={value:g} {unit} is out of range [{low:g}, {high:g}]")
            object.__setattr__(self, axis, float(value))

    @classmethod
    def rates(cls, pitch_deg_s: float, yaw_deg_s: float) -> GimbalPointing:
        """Turn at these rates (deg/s, pitch positive up, yaw positive right) until the next frame says otherwise."""
        return cls(RATE, pitch_deg_s, yaw_deg_s)

    @classmethod
    def angles(cls, pitch_deg: float, yaw_deg: float = 0.0) -> GimbalPointing:
        """Look at these angles (degrees: pitch from level, positive up; yaw from the nose, positive right)."""
        return cls(ANGLE, pitch_deg, yaw_deg)

    def describe(self) -> str:
        """``rates pitch -4.0 yaw 12.5 deg/s`` or ``angles pitch -45.0 yaw 0.0 deg``."""
        unit = "deg/s" if self.mode == RATE else "deg"
        return f"{self.mode}s pitch {self.pitch:.1f} yaw {self.yaw:.1f} {unit}"
