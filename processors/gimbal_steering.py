"""Target offset in the image -> gimbal rates that bring it to the frame centre (the trackers' ``follow="gimbal"``).

The target's pixel is turned into a direction (the camera model's ray, or a 62 degree field of view without one),
seen from the gimbal's pitch at the frame's capture into the pitch and yaw the gimbal would need to look straight at
it; each rate is ``gain`` times the angle still to turn (the yaw still to turn does not depend on where the gimbal
points in yaw, so its yaw is not needed). Working in the
gimbal's own angles, not in the image, keeps it right when the camera looks steeply down, where turning the yaw
spins the image about its centre instead of moving it sideways. Without the gimbal's attitude the image offsets are
taken as the angles to turn (right at small angles from the horizon).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from uav_values.gimbal import MAX_RATE_DEG_S, GimbalPointing

DEFAULT_HFOV_DEG = 62.0
"""The field of view assumed without a camera model."""


@dataclass
class GimbalSteering:
    """Proportional gimbal rates from a target box.

    Attributes:
        gain: deg/s per degree still to turn (2: a target 5 degrees off turns the gimbal at 10 deg/s).
        dead_band: degrees below which an axis is not turned.
        max_rate: clamp of each rate, deg/s.
    """

    gain: float = 2.0
    dead_band: float = 0.3
    max_rate: float = 60.0

    def __post_init__(self) -> None:
        if not (self.gain > 0 and self.dead_band >= 0 and 0 < self.max_rate <= MAX_RATE_DEG_S):
            raise ValueError(f"gimbal steering: gain > 0, dead_band >= 0, 0 < max_rate <= {MAX_RATE_DEG_S:g} "
                             f"(got {self.gain}, {self.dead_band}, {self.max_rate})")

    def rates(self, box: tuple[float, float, float, float], size: tuple[int, int], camera: Any = None,
              gimbal_pitch: float | None = None) -> GimbalPointing:
        """The rates that turn the gimbal towards the centre of ``box`` in a ``size`` (width, height) frame.

        Args:
            camera: the frame's camera model (``tmMgr.camera()``), or None.
            gimbal_pitch: the gimbal's pitch from the horizon at the frame's capture, degrees, or None.
        """
        x, y, w, h = box
        u, v = x + w / 2, y + h / 2
        if camera is not None:
            right, down = camera.angles(u, v)
        else:
            focal = size[0] / 2 / math.tan(math.radians(DEFAULT_HFOV_DEG / 2))
            right, down = math.atan2(u - size[0] / 2, focal), math.atan2(v - size[1] / 2, focal)
        if gimbal_pitch is None:
            return GimbalPointing.rates(self._rate(-math.degrees(down)), self._rate(math.degrees(right)))
        pitch = math.radians(gimbal_pitch)
        # the ray (forward 1, right tan(right), down tan(down)) in the gimbal's frame, turned by its pitch
        f, r, d = 1.0, math.tan(right), math.tan(down)
        f, d = f * math.cos(pitch) + d * math.sin(pitch), -f * math.sin(pitch) + d * math.cos(pitch)
        want_pitch, turn_yaw = math.atan2(-d, math.hypot(f, r)), math.atan2(r, f)
        return GimbalPointing.rates(self._rate(math.degrees(want_pitch - pitch)), self._rate(math.degrees(turn_yaw)))

    def _rate(self, offset_deg: float) -> float:
        if abs(offset_deg) < self.dead_band:
            return 0.0
        return max(-self.max_rate, min(self.max_rate, self.gain * offset_deg))
