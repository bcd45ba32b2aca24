"""Whether an output the processor gave can be true, checked at its relay just before it is sent.

The value types check themselves when they are built (:mod:`uav_values.landing_target`, :mod:`uav_values.gimbal`),
but a processor in the platform's process (``isolation = "thread"``) can change the object afterwards
(``object.__setattr__``; from its own process the wire rebuilds it with the check), and a target that type-checks
can still be impossible. So each frame, the relay asks here:

* a landing target: every field again (the value type's own check, on a copy the processor does not hold); the
  frame it was seen in; its direction inside the camera's view and below the vehicle's horizon; its distance
  against the vehicle's height at the capture (:data:`HEIGHT_TOLERANCE`); and the pad's place relative to the
  vehicle no further from the last accepted one than the vehicle's speed explains (:data:`JUMP_SLACK_M`);
* a gimbal pointing: its mode and the ranges the contract states, again on a copy.

An answer is the checked copy or the reason it is refused; the relay counts the reason and writes it in
frames.csv, and :class:`RefusalRun` says when a run of them stops the output.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from uav_values.gimbal import GimbalPointing
from uav_values.landing_target import LandingTarget

if TYPE_CHECKING:
    from controllers.base import Telemetry
    from uav_values.camera import CameraModel

REFUSALS_TO_STOP = 10
"""Refusals in a row that stop an output, as a processor fault does (a third of a second at 30 FPS)."""

HEIGHT_TOLERANCE = (0.5, 2.0)
"""The pad's drop below the camera (its distance along the line of sight, straight down) may differ from the
vehicle's height above home by this fraction of the height or these metres, whichever is more (a pad on a box, on
a slope, a height a metre off at take-off); the processor's own size check is tighter (25 %)."""

MIN_DEPRESSION = 0.1
"""A pad must be at least this far below the vehicle's horizon (the down component of the unit line of sight,
about 6 degrees): nearer the horizon no distance to it can be judged, and a landing pad is below."""

VIEW_MARGIN = 1.1
"""The line of sight may lie this much beyond the image's edge (as the tangent of its angle off the axis): a pad's
centre just outside a distorted edge is still a pad in view; one far outside it was not seen in this image."""

JUMP_SLACK_M = (1.0, 0.3)
"""Between two frames the pad's place relative to the vehicle may move by what the vehicle's speed (plus
:data:`SPEED_MARGIN_MS`) explains, plus these metres and this fraction of its distance: the estimate's noise and
the attitude's lag at the capture (telemetry at 10 Hz; ``bench_precland.py`` at load 14 saw an honest 2.1 m in
0.06 s at about 6.5 m, in wind)."""

SPEED_MARGIN_MS = 2.0
"""Added to the vehicle's speed at the capture (telemetry's velocity is a tenth of a second old)."""

JUMP_MEMORY_S = 1.0
"""An accepted target older than this is no reference for the next (the pad may have been out of view)."""

Vector3 = tuple[float, float, float]


class RefusalRun:
    """An output's refusals: how many, the last reason, and how many in a row (:data:`REFUSALS_TO_STOP` stop it)."""

    def __init__(self, limit: int = REFUSALS_TO_STOP) -> None:
        self.limit = limit
        self.refused = 0
        """Refusals since the start."""
        self.in_a_row = 0
        self.last = ""
        """The last refusal's reason ("" before any)."""

    def refuse(self, reason: str) -> bool:
        """Count a refusal; True while the run is :attr:`limit` long or longer: the output must stop."""
        self.refused += 1
        self.in_a_row += 1
        self.last = reason
        return self.in_a_row >= self.limit

    def accept(self) -> None:
        self.in_a_row = 0


@dataclass(frozen=True, slots=True)
class Judged:
    """A landing target the relay may send (a copy the processor does not hold), or why not."""

    target: LandingTarget | None
    reason: str = ""


class LandingCheck:
    """Judges each frame's landing target against the camera model and the telemetry at the frame's capture,
    remembering the last accepted one (:data:`JUMP_MEMORY_S`)."""

    def __init__(self) -> None:
        self._last: tuple[int, Vector3] | None = None
        """(capture ns, pad relative to the vehicle in NED metres) of the last accepted target."""
        self._view: tuple[CameraModel, tuple[float, float, float, float], tuple[Vector3, ...]] | None = None
        """The camera last judged against: its view's limits (:func:`_view_limits`) and its rotation's rows."""

    def judge(self, target: LandingTarget, frame_seq: int, capture_ns: int, camera: CameraModel,
              at_capture: Telemetry) -> Judged:
        """``target`` as given after the frame ``frame_seq`` captured at ``capture_ns``: a checked copy, or why not."""
        try:  # every field again, whatever was done to the object after it was built
            copy = LandingTarget(target.direction, target.distance_m, target.frame_seq, target.frame)
        except (TypeError, ValueError) as exc:
            return Judged(None, str(exc))
        if copy.frame_seq is not None and copy.frame_seq != frame_seq:
            return Judged(None, f"seen in frame {copy.frame_seq}, not this one (its capture time is gone)")
        if self._view is None or self._view[0] is not camera:
            self._view = camera, _view_limits(camera), tuple(map(tuple, camera.rotation_body_camera.tolist()))
        reason = _outside_view(copy.direction, self._view[1])
        if reason:
            return Judged(None, reason)
        t = at_capture
        (a, b, c), (d, e, f), (g, h, i) = self._view[2]
        x, y, z = copy.direction
        body = (a * x + b * y + c * z, d * x + e * y + f * z, g * x + h * y + i * z)
        ned = _ned(body, t.roll_deg or 0.0, t.pitch_deg or 0.0, t.yaw_deg or 0.0)
        if ned[2] < MIN_DEPRESSION:
            return Judged(None, f"the line of sight is {math.degrees(math.asin(max(-1.0, ned[2]))):.0f} deg below "
                                "the horizon: a landing pad is below the vehicle")
        height = t.rel_alt_m
        distance = copy.distance_m
        if distance is not None:
            if height is None:
                return Judged(None, "no height at the capture to check the distance against")
            drop = distance * ned[2]
            allowed = max(HEIGHT_TOLERANCE[0] * abs(height), HEIGHT_TOLERANCE[1])
            if abs(drop - height) > allowed:
                return Judged(None, f"distance {distance:.1f} m puts the pad {drop:.1f} m below the camera, but the "
                                    f"vehicle is {height:.1f} m above home")
        elif height is not None:
            distance = max(height, 0.0) / ned[2]  # the line of sight meets the ground
        if distance is None:
            return Judged(copy)  # nothing to compare with: a direction alone, without a height
        reason = self._jump(capture_ns, (distance * ned[0], distance * ned[1], distance * ned[2]), t)
        return Judged(None, reason) if reason else Judged(copy)

    def _jump(self, capture_ns: int, pad: Vector3, t: Telemetry) -> str:
        """Why the pad at ``pad`` (relative to the vehicle, NED) cannot follow the last accepted one, or ""."""
        last, self._last = self._last, (capture_ns, pad)
        if last is None:
            return ""
        dt = (capture_ns - last[0]) / 1e9
        if not 0 < dt <= JUMP_MEMORY_S:
            return ""
        speed = math.sqrt(sum(v * v for v in (t.vn_ms or 0.0, t.ve_ms or 0.0, t.vd_ms or 0.0)))
        jump = math.dist(pad, last[1])
        allowed = JUMP_SLACK_M[0] + JUMP_SLACK_M[1] * math.sqrt(sum(p * p for p in pad)) \
            + (speed + SPEED_MARGIN_MS) * dt
        if jump <= allowed:
            return ""
        self._last = last  # the refused one is no reference
        return (f"the pad moved {jump:.1f} m relative to the vehicle in {dt:.2f} s; the vehicle's speed "
                f"({speed:.1f} m/s) explains {allowed:.1f} m")


def _outside_view(direction: Vector3, limits: tuple[float, float, float, float]) -> str:
    """Why ``direction`` cannot have been seen in an image reaching ``limits`` (:func:`_view_limits`), or ""."""
    left, right, up, down = limits
    x, y, z = direction
    tx, ty = x / z, y / z
    if -left <= tx <= right and -up <= ty <= down:
        return ""
    return (f"direction {math.degrees(math.atan(tx)):+.0f} deg right, {math.degrees(math.atan(ty)):+.0f} deg "
            "down is outside the camera's view")


def _ned(body: Vector3, roll_deg: float, pitch_deg: float, yaw_deg: float) -> Vector3:
    """A body-frame (FRD) vector in NED: :func:`~controllers.landing_target_message.rotation_ned_body` applied to one
    vector, in scalar math (NumPy's calls alone would be most of a frame's budget for the checks)."""
    r, p, y = math.radians(roll_deg), math.radians(pitch_deg), math.radians(yaw_deg)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    forward, right, down = body
    right, down = cr * right - sr * down, sr * right + cr * down  # roll about the forward axis
    forward, down = cp * forward + sp * down, -sp * forward + cp * down  # pitch about the right axis
    return cy * forward - sy * right, sy * forward + cy * right, down  # yaw about the down axis


def _view_limits(camera: CameraModel) -> tuple[float, float, float, float]:
    """How far (tangent off the optical axis) the image reaches left, right, up and down, with :data:`VIEW_MARGIN`;
    the border's pixels undistorted."""
    w, h = camera.width, camera.height
    border = [(u, v) for u in (0.0, w / 2, float(w)) for v in (0.0, h / 2, float(h)) if (u, v) != (w / 2, h / 2)]
    rays = camera.pixels_to_rays(np.array(border))
    tx, ty = rays[:, 0] / rays[:, 2], rays[:, 1] / rays[:, 2]
    return tuple(VIEW_MARGIN * float(max(abs(v), 1e-6))  # type: ignore[return-value]
                 for v in (tx.min(), tx.max(), ty.min(), ty.max()))


def judge_gimbal(pointing: GimbalPointing) -> GimbalPointing | str:
    """``pointing`` checked again against the contract's ranges: a copy the processor does not hold, or why not."""
    try:
        return GimbalPointing(pointing.mode, pointing.pitch, pointing.yaw)
    except (TypeError, ValueError) as exc:
        return str(exc)
