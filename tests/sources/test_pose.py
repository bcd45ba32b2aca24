"""PoseTrack: telemetry samples in, the pose at a frame's capture time out."""

from __future__ import annotations

import math

import pytest

from sources.pose import MAX_EXTRAPOLATION_S, PoseTrack

MS = 1_000_000


def moving_track() -> PoseTrack:
    """North at 1 m/s, yaw turning at 100 deg/s across +-180; samples every 20 ms from t = 0 to 100 ms."""
    track = PoseTrack()
    for i in range(6):
        t = i * 20 * MS
        track.add_position(t, 0.02 * i, 5.0, -10.0)
        yaw = (170.0 + 2.0 * i + 180.0) % 360.0 - 180.0  # 170, 172, ..., 178, -180
        track.add_attitude(t + 5 * MS, 1.0, -2.0, yaw)  # attitude samples arrive 5 ms after the positions
    return track


def test_no_pose_until_both_position_and_attitude_arrived() -> None:
    track = PoseTrack()
    assert track(0) is None
    track.add_position(0, 1.0, 2.0, -3.0)
    assert track(0) is None
    track.add_attitude(0, 0.0, 0.0, 90.0)
    assert track(0).pose.n == 1.0


def test_interpolates_between_samples_and_across_the_yaw_wrap() -> None:
    at = moving_track()(90 * MS)
    assert at.extrapolated_s == 0.0
    assert at.pose.n == pytest.approx(0.09) and at.pose.e == 5.0 and at.pose.d == -10.0
    assert at.pose.yaw == pytest.approx(178.5)  # between 178 and -180, the short way round
    assert (at.pose.roll, at.pose.pitch) == pytest.approx((1.0, -2.0))
    assert moving_track()(106 * MS).pose.yaw == pytest.approx(-179.9)


def test_extrapolates_a_little_and_says_by_how_much() -> None:
    track = moving_track()
    at = track(120 * MS)  # 20 ms after the last position, 15 ms after the last attitude
    assert at.extrapolated_s == pytest.approx(0.020)
    assert at.pose.n == pytest.approx(0.12)
    assert at.pose.yaw == pytest.approx(-178.5)


def test_a_stale_track_stops_extrapolating_but_reports_the_age() -> None:
    at = moving_track()(2_000 * MS)
    assert at.extrapolated_s == pytest.approx(1.9)
    assert at.pose.n == pytest.approx(0.10 + MAX_EXTRAPOLATION_S)  # held at the limit, not flown off to 2 m


def test_out_of_order_and_non_finite_samples_are_ignored() -> None:
    track = moving_track()
    track.add_position(50 * MS, 99.0, 99.0, 99.0)
    track.add_position(200 * MS, math.nan, 0.0, 0.0)
    track.add_attitude(200 * MS, 0.0, math.inf, 0.0)
    at = track(100 * MS)
    assert at.pose.n == pytest.approx(0.10) and at.extrapolated_s == 0.0


def test_before_the_first_sample_the_first_pose_holds() -> None:
    at = moving_track()(-50 * MS)
    assert at.pose.n == 0.0 and at.pose.yaw == pytest.approx(170.0) and at.extrapolated_s == 0.0
