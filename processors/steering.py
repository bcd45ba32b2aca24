"""Target offset in the image -> body-frame velocity vector, shared by the tracker and YOLO follow.

Conventions (the contract's): body frame, ``vx`` forward, ``vy`` right, m/s; image x grows to the
right, y grows downward; the camera is mounted aligned with the body (image right = body right).

* ``camera="down"`` (nadir camera, image top = forward): a target right of centre asks for +vy,
  a target above centre asks for +vx, so the vehicle moves until the target sits under it.
* ``camera="forward"`` (looking ahead): a target right of centre asks for +vy (side-step to keep
  it centred); ``vx`` keeps the target's apparent size at the size it had when it was selected
  (smaller than that -> it moved away -> fly forward).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable
from dataclasses import dataclass

import cv2
import numpy as np

from uav_values.box import Box

logger = logging.getLogger(__name__)

CAMERA_ORIENTATIONS = ("down", "forward")
"""Accepted values of ``camera``."""



def as_box(values: Iterable[float]) -> Box:
    """Four values (x, y, w, h), e.g. an OpenCV rect or a scaled box, as a :data:`Box` of floats."""
    x, y, w, h = values
    return float(x), float(y), float(w), float(h)

Vector = tuple[float, float, float]
"""(vx, vy, t): body-frame m/s and seconds."""


@dataclass
class Steering:
    """Proportional steering from a target box to a body-frame velocity.

    Attributes:
        camera: "down" or "forward" (see the module docstring).
        gain: m/s per unit of normalised offset (offset of 1 = target at the frame edge).
        dead_band: normalised offset below which an axis asks for zero speed.
        max_speed: clamp of |vx| and |vy| in m/s (the platform clamps again; <= 1).
        t: duration of each vector in seconds (short: a new one comes with every frame).
    """

    camera: str = "down"
    gain: float = 0.8
    dead_band: float = 0.05
    max_speed: float = 1.0
    t: float = 0.5

    def __post_init__(self) -> None:
        if self.camera not in CAMERA_ORIENTATIONS:
            raise ValueError(f"camera must be one of {CAMERA_ORIENTATIONS}, got {self.camera!r}")
        self.max_speed = min(abs(self.max_speed), 1.0)
        self.t = float(min(max(self.t, 0.05), 2.0))

    def vector(self, box: Box, frame_size: tuple[int, int], ref_height: float | None = None) -> Vector:
        """Velocity that brings the target towards the frame centre.

        Args:
            box: target box (x, y, w, h) in frame pixels.
            frame_size: (width, height) of the frame.
            ref_height: for ``camera="forward"``, the box height to keep (pixels); None -> vx = 0.

        Returns:
            (vx, vy, t), |vx|, |vy| <= max_speed.
        """
        ex, ey = normalised_offset(box, frame_size)
        vy = self._axis(ex)
        if self.camera == "down":
            vx = self._axis(-ey)
        elif ref_height and box[3] > 0:
            vx = self._axis(1.0 - box[3] / ref_height)
        else:
            vx = 0.0
        return vx, vy, self.t

    def _axis(self, err: float) -> float:
        if abs(err) < self.dead_band:
            return 0.0
        return float(np.clip(self.gain * err, -self.max_speed, self.max_speed))

    def scale_gain(self, factor: float) -> None:
        """Multiply the gain (F3/F4 of the processors), kept within [0.05, 5]."""
        self.gain = float(np.clip(self.gain * factor, 0.05, 5.0))
        logger.info("Steering gain now %.2f", self.gain)


@dataclass
class Ramp:
    """Eases vectors in: each velocity moves from the last by at most ``accel`` m/s per second of the frames' time
    (direction kept); after no vector (no target: the vehicle holds) the next starts from standstill. A 1 m/s step
    tilts the vehicle ~14 degrees at once (its ~0.4 s velocity response), which swings a down camera's view by a
    fifth of the frame: a target near the edge, as the quick start's car is when autonomy goes on, leaves it."""

    accel: float = 1.0
    _velocity: tuple[float, float] = (0.0, 0.0)
    _t: float | None = None

    def __call__(self, vector: Vector | None, now: float) -> Vector | None:
        """``vector`` eased in at ``now`` (s: the frame's capture time, so a replay eases alike)."""
        dt = 0.0 if self._t is None else min(max(now - self._t, 0.0), 1.0)
        self._t = now
        if vector is None:
            self._velocity = (0.0, 0.0)
            return None
        (ux, uy), (vx, vy, t) = self._velocity, vector
        change = math.hypot(vx - ux, vy - uy)
        k = min(1.0, self.accel * dt / change) if change > 0 else 1.0
        self._velocity = (ux + k * (vx - ux), uy + k * (vy - uy))
        return *self._velocity, t


def velocity_toward(
    forward_m: float, right_m: float, gain: float, max_speed: float, dead_band_m: float, t: float
) -> Vector:
    """Proportional velocity towards a point ``forward_m``/``right_m`` away (body frame).

    Speed is ``gain`` (1/s) x distance, scaled down (direction kept) so neither component exceeds
    ``max_speed``; inside ``dead_band_m`` the velocity is zero.
    """
    if math.hypot(forward_m, right_m) < dead_band_m:
        return 0.0, 0.0, t
    vx, vy = gain * float(forward_m), gain * float(right_m)
    k = min(1.0, max_speed / max(abs(vx), abs(vy), 1e-9))
    return vx * k, vy * k, float(t)


def normalised_offset(box: Box, frame_size: tuple[int, int]) -> tuple[float, float]:
    """Offset of the box centre from the frame centre, -1..1 on each axis (x right, y down)."""
    w, h = frame_size
    cx = box[0] + box[2] / 2.0
    cy = box[1] + box[3] / 2.0
    return (cx - w / 2.0) / (w / 2.0), (cy - h / 2.0) / (h / 2.0)


def draw_target(
    frame: np.ndarray,
    box: Box,
    vector: Vector | None,
    color: tuple[int, int, int] = (0, 255, 0),
    label: str | None = None,
) -> None:
    """Draw box, its centre and label, then :func:`draw_vector`, in place."""
    x, y, bw, bh = (int(round(v)) for v in box)
    cv2.rectangle(frame, (x, y), (x + bw, y + bh), color, 2)
    centre = (x + bw // 2, y + bh // 2)
    cv2.circle(frame, centre, 3, color, -1)
    if label:
        cv2.putText(frame, label, (x, max(12, y - 4)), cv2.FONT_HERSHEY_SIMPLEX, 0.45, color, 1, cv2.LINE_AA)
    draw_vector(frame, vector)


def draw_vector(frame: np.ndarray, vector: Vector | None) -> None:
    """Draw the frame-centre cross and the commanded vector as an arrow from the centre, in place.

    A 1 m/s component spans a quarter of the frame; the direction is drawn as seen by a nadir camera
    (forward = up).
    """
    h, w = frame.shape[:2]
    fc = (w // 2, h // 2)
    cv2.drawMarker(frame, fc, (255, 255, 255), cv2.MARKER_CROSS, 12, 1)
    if vector is not None:
        vx, vy, _ = vector
        tip = (fc[0] + int(vy * w / 4), fc[1] - int(vx * h / 4))
        if math.hypot(tip[0] - fc[0], tip[1] - fc[1]) >= 2:
            cv2.arrowedLine(frame, fc, tip, (0, 0, 255), 2, tipLength=0.25)
