"""The shared target-offset -> body-frame vector logic."""

from __future__ import annotations

import math

import numpy as np
import pytest

from processors.steering import Ramp, Steering, draw_target, velocity_toward

FRAME = (640, 480)


def _box_at(cx: float, cy: float, h: float = 40.0) -> tuple[float, float, float, float]:
    return cx - 20.0, cy - h / 2, 40.0, h


@pytest.mark.parametrize(
    ("centre", "expected"),
    [((480, 240), (0.0, 0.4)), ((160, 240), (0.0, -0.4)), ((320, 120), (0.4, 0.0)), ((320, 360), (-0.4, 0.0))],
    ids=["right", "left", "above", "below"],
)
def test_down_camera_moves_over_the_target(centre: tuple[int, int], expected: tuple[float, float]) -> None:
    vx, vy, t = Steering("down", gain=0.8).vector(_box_at(*centre), FRAME)
    assert (vx, vy) == pytest.approx(expected)
    assert t == 0.5


def test_forward_camera_keeps_size_and_centres_sideways() -> None:
    steer = Steering("forward", gain=1.0)
    vx, vy, _ = steer.vector(_box_at(480, 100, h=20.0), FRAME, ref_height=40.0)  # smaller: farther away
    assert vx == pytest.approx(0.5) and vy == pytest.approx(0.5)
    vx, _, _ = steer.vector(_box_at(320, 240, h=80.0), FRAME, ref_height=40.0)  # bigger: too close
    assert vx == pytest.approx(-1.0)
    assert steer.vector(_box_at(320, 100), FRAME, ref_height=None)[0] == 0.0


def test_dead_band_clamp_and_gain_limits() -> None:
    steer = Steering("down", gain=3.0, dead_band=0.1, max_speed=0.7)
    assert steer.vector(_box_at(330, 245), FRAME)[:2] == (0.0, 0.0)
    assert steer.vector(_box_at(630, 10), FRAME)[:2] == (pytest.approx(0.7), pytest.approx(0.7))
    for _ in range(20):
        steer.scale_gain(1.25)
    assert steer.gain == 5.0
    with pytest.raises(ValueError, match="camera"):
        Steering("up")


def test_velocity_toward_keeps_direction_when_clamped() -> None:
    vx, vy, t = velocity_toward(4.0, -2.0, gain=1.0, max_speed=1.0, dead_band_m=0.2, t=1.0)
    assert (vx, vy, t) == (1.0, -0.5, 1.0)
    assert velocity_toward(0.1, 0.1, 1.0, 1.0, 0.2, 1.0) == (0.0, 0.0, 1.0)
    vx, vy, _ = velocity_toward(0.6, 0.8, 0.5, 1.0, 0.2, 1.0)
    assert math.hypot(vx, vy) == pytest.approx(0.5)


def test_draw_target_draws_box_and_arrow() -> None:
    frame = np.zeros((480, 640, 3), np.uint8)
    draw_target(frame, _box_at(480, 240), (0.0, 0.4, 0.5), label="x")
    assert (frame[220:261, 460] == (0, 255, 0)).all()  # left edge of the box
    assert (frame[240, 330:350] == (0, 0, 255)).any()  # arrow pointing right from the centre


def test_a_ramp_eases_a_step_in_at_its_acceleration_and_starts_again_from_standstill() -> None:
    ramp = Ramp(accel=1.0)
    assert ramp((1.0, 0.0, 0.5), 10.0) == (0.0, 0.0, 0.5)  # the first vector: no time has passed yet
    vx, vy, t = ramp((1.0, 1.0, 0.5), 10.5)  # 0.5 s at 1 m/s/s: 0.5 m/s towards (1, 1), direction kept
    assert (round(vx, 3), round(vy, 3), t) == (0.354, 0.354, 0.5)
    assert ramp((0.2, 0.3, 0.5), 11.5) == (0.2, 0.3, 0.5)  # within reach: as asked
    assert ramp(None, 11.6) is None
    vx, _, _ = ramp((1.0, 0.0, 0.5), 11.7)  # after no vector the vehicle held: from standstill again
    assert round(vx, 3) == 0.1
