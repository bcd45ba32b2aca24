"""The target's ground velocity and heading from its geo-located positions on the frame clock."""

from __future__ import annotations

import math

import numpy as np
import pytest

from uav_tui.flight.geolocate import EARTH_RADIUS_M, HORIZON, OK, GeoFix
from uav_tui.flight.target_motion import GAP_S, MIN_FIXES, TargetMotion

S = 1_000_000_000
FPS = 15


def _fix(north: float, east: float) -> GeoFix:
    lat = 47.0 + math.degrees(north / EARTH_RADIUS_M)
    lon = 8.0 + math.degrees(east / (EARTH_RADIUS_M * math.cos(math.radians(47.0))))
    return GeoFix(OK, lat, lon, 488.0, 0.6, 0.0, 0.0, 20.0, "home")


def _drive(motion: TargetMotion, seconds: float, vel_n: float, vel_e: float, *, start_s: float = 0.0,
           jitter_m: float = 0.0, seed: int = 0) -> int:
    """A target driving at (vel_n, vel_e) seen at 15 fps, each position off by ``jitter_m`` (1 sigma); the last t."""
    rng = np.random.default_rng(seed)
    t_ns = 0
    for i in range(int(seconds * FPS)):
        t = start_s + i / FPS
        t_ns = int(t * S)
        noise = rng.normal(0.0, jitter_m, 2)
        motion.add(t_ns, _fix(vel_n * t + noise[0], vel_e * t + noise[1]))
    return t_ns


def test_a_driving_target_has_its_velocity_and_heading_despite_jitter() -> None:
    motion = TargetMotion()
    # 3 m/s towards 030 deg, each position off by 0.15 m: a difference of two frames would be off by ~3 m/s
    speed, heading = 3.0, math.radians(30.0)
    now = _drive(motion, 4.0, speed * math.cos(heading), speed * math.sin(heading), jitter_m=0.15, seed=1)
    found = motion.motion(now)
    assert math.hypot(found.vel_n, found.vel_e) == pytest.approx(speed, abs=0.15)
    assert found.heading_rad == pytest.approx(heading, abs=math.radians(3.0))
    assert 0.01 < found.vel_acc < 0.15  # from the fit's residuals: 0.15 m over 2 s and 30 frames
    assert found.heading_acc_rad == pytest.approx(math.atan2(found.vel_acc, speed), rel=0.1)


def test_a_parked_target_has_a_velocity_near_zero_and_no_heading() -> None:
    motion = TargetMotion()
    now = _drive(motion, 3.0, 0.0, 0.0, jitter_m=0.1, seed=2)
    found = motion.motion(now)
    assert math.hypot(found.vel_n, found.vel_e) < 0.15 and math.isfinite(found.vel_acc)
    assert math.isnan(found.heading_rad) and math.isnan(found.heading_acc_rad)


def test_not_enough_positions_give_nan() -> None:
    motion = TargetMotion()
    assert math.isnan(motion.motion(0).vel_n)  # none
    now = _drive(motion, (MIN_FIXES - 1) / FPS, 2.0, 0.0)
    assert math.isnan(motion.motion(now).vel_n)  # too few
    motion = TargetMotion()
    for i in range(10):  # many, but within 0.1 s
        motion.add(i * S // 100, _fix(0.02 * i, 0.0))
    assert math.isnan(motion.motion(S // 10).vel_n)
    motion.add(2 * S // 10, GeoFix(HORIZON))  # a frame without a position adds nothing
    assert math.isnan(motion.motion(S // 5).vel_n)


def test_a_target_lost_for_a_while_starts_a_new_track() -> None:
    motion = TargetMotion()
    now = _drive(motion, 3.0, 2.0, 0.0)
    assert motion.motion(now).vel_n == pytest.approx(2.0, abs=1e-6)
    assert math.isnan(motion.motion(now + int((GAP_S + 0.1) * S)).vel_n)  # nothing seen since: unknown
    # found again 1.5 s later, driving east (another car, maybe): only the new positions count
    now = _drive(motion, 1.0, 0.0, 2.0, start_s=now / S + 1.5)
    found = motion.motion(now)
    assert (found.vel_n, found.vel_e) == (pytest.approx(0.0, abs=1e-6), pytest.approx(2.0, abs=1e-6))
    motion.reset()
    assert math.isnan(motion.motion(now).vel_n)
