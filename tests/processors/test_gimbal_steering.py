"""Gimbal rates from a target box: towards the target, zero on it, and right where the camera looks straight down."""

from __future__ import annotations

import math

import pytest

from processors.gimbal_steering import GimbalSteering
from uav_values.camera import CameraModel, Mount

SIZE = (640, 480)
CAMERA = CameraModel.from_hfov(*SIZE, 62.0, Mount(0.0, gimbal=True))


def _box_at(u: float, v: float) -> tuple[float, float, float, float]:
    return u - 10, v - 10, 20, 20


def test_a_target_right_and_below_turns_the_gimbal_right_and_down() -> None:
    steering = GimbalSteering(gain=2.0)
    right_down = steering.rates(_box_at(480, 360), SIZE, CAMERA, -30.0)
    assert right_down.pitch < 0 and right_down.yaw > 0
    centred = steering.rates(_box_at(320, 240), SIZE, CAMERA, -30.0)
    assert (centred.pitch, centred.yaw) == (0.0, 0.0)
    level = steering.rates(_box_at(320 + CAMERA.fx * math.tan(math.radians(5)), 240), SIZE, CAMERA, 0.0)
    assert (level.pitch, level.yaw) == pytest.approx((0.0, 10.0))  # 5 degrees right at the horizon: 2 x 5 deg/s


def test_looking_straight_down_a_target_to_the_right_is_reached_by_yawing_towards_it() -> None:
    steering = GimbalSteering(gain=2.0, max_rate=180.0)
    rates = steering.rates(_box_at(480, 240), SIZE, CAMERA, -90.0)  # right of the nadir view
    assert rates.yaw == pytest.approx(180.0) and rates.pitch > 0  # yaw 90 to face it (clamped), pitch up to it
    without = steering.rates(_box_at(480, 240), SIZE)  # no camera model nor attitude: the image offsets
    assert without.yaw > 0 and without.pitch == 0.0


def test_rates_are_clamped_and_small_offsets_ignored() -> None:
    steering = GimbalSteering(gain=10.0, dead_band=1.0, max_rate=30.0)
    far = steering.rates(_box_at(630, 470), SIZE, CAMERA, 0.0)
    assert (far.pitch, far.yaw) == (-30.0, 30.0)
    near = steering.rates(_box_at(321, 240), SIZE, CAMERA, 0.0)
    assert (near.pitch, near.yaw) == (0.0, 0.0)
    with pytest.raises(ValueError, match="max_rate"):
        GimbalSteering(max_rate=500.0)
