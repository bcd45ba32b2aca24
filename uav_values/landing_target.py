"""The landing target: the contract's second optional output (``getLandingTarget() -> LandingTarget | None``).

A processor that sees a landing pad returns, for the frame just processed, the direction to the pad's centre
in the **camera frame** (OpenCV's: x right in the image, y down in the image, z along the optical axis) as a
unit vector, and the distance in metres when it knows it. The platform turns it into each autopilot's
LANDING_TARGET with the camera model's mounting and the attitude at the frame's capture; the processor never
needs to know the vehicle, the mount or the autopilot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

CAMERA_FRAME = "camera"
"""The one coordinate frame a :class:`LandingTarget` is given in: x right, y down (image), z ahead (optical axis)."""

MAX_DISTANCE_M = 10_000.0
"""Distances beyond this are not a landing pad: :class:`LandingTarget` refuses them."""


@dataclass(frozen=True, slots=True)
class LandingTarget:
    """Where the landing pad is, as seen in one frame.

    Args:
        direction: unit vector (x right, y down, z ahead) from the camera to the pad's centre, camera frame;
            normalised on construction. The pad must be in front of the camera (z > 0).
        distance_m: camera to pad centre in metres, or None when the processor does not know it.
        frame_seq: the capture number (``tmMgr.snapshot().frame_seq``) of the frame the pad was seen in; None
            means the frame just processed.

    Raises:
        ValueError: a direction that is not three finite numbers in front of the camera, or a distance that is
            not a positive finite number.
    """

    direction: tuple[float, float, float]
    distance_m: float | None = None
    frame_seq: int | None = None
    frame: str = CAMERA_FRAME
    """The coordinate frame of ``direction``: always :data:`CAMERA_FRAME`."""

    def __post_init__(self) -> None:
        x, y, z = (float(c) for c in self.direction)
        norm = math.sqrt(x * x + y * y + z * z)
        if not math.isfinite(norm) or norm <= 0 or z <= 0:
            raise ValueError(f"landing target direction {self.direction!r} must be 3 finite numbers with z > 0 "
                             "(camera frame: x right, y down, z ahead)")
        object.__setattr__(self, "direction", (x / norm, y / norm, z / norm))
        if self.distance_m is not None:
            distance = float(self.distance_m)
            if not math.isfinite(distance) or not 0 < distance <= MAX_DISTANCE_M:
                raise ValueError(f"landing target distance {self.distance_m!r} must be in (0, {MAX_DISTANCE_M:g}] m")
            object.__setattr__(self, "distance_m", distance)
        if self.frame != CAMERA_FRAME:
            raise ValueError(f"landing target frame {self.frame!r}: only {CAMERA_FRAME!r} is supported")

    @classmethod
    def from_angles(cls, angle_x: float, angle_y: float, distance_m: float | None = None,
                    frame_seq: int | None = None) -> LandingTarget:
        """From angles (radians) off the optical axis, right (``angle_x``) and down (``angle_y``) in the image.

        Raises:
            ValueError: an angle that is not finite or not within +-pi/2 (beyond it the pad would be behind the
                camera, and ``tan`` would fold it back in front: pi would read as straight ahead).
        """
        for name, angle in (("angle_x", angle_x), ("angle_y", angle_y)):
            if not (math.isfinite(angle) and abs(angle) < math.pi / 2):
                raise ValueError(f"landing target {name}={angle!r} rad must be within (-pi/2, pi/2): an angle off "
                                 "the optical axis, in radians (not degrees)")
        return cls((math.tan(angle_x), math.tan(angle_y), 1.0), distance_m, frame_seq)

    def stamp(self, frame_seq: int) -> None:
        """The platform's, after the frame ``frame_seq`` this target was returned for: sets :attr:`frame_seq` when
        it is None, in place and once, so this same object returned after a later frame still says it was seen in
        that first frame (and is not sent as the later frame's)."""
        if self.frame_seq is None:
            object.__setattr__(self, "frame_seq", frame_seq)

    @property
    def angles(self) -> tuple[float, float]:
        """(right, down) angles in radians off the optical axis (``CameraModel.angles`` of the pad's pixel)."""
        x, y, z = self.direction
        return math.atan2(x, z), math.atan2(y, z)

    @property
    def position_m(self) -> tuple[float, float, float] | None:
        """The pad's centre in the camera frame, metres, when the distance is known."""
        if self.distance_m is None:
            return None
        x, y, z = self.direction
        return x * self.distance_m, y * self.distance_m, z * self.distance_m
