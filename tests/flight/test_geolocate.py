"""Geo-location of a box against the built-in simulator's truth, and what it says on bad input."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from controllers.base import Telemetry
from controllers.mavsdk.telemetry import from_distance_sensor, from_position
from tests.flight.geo_helpers import HOME, car_views
from uav_tui.flight import geolocate
from uav_tui.recording.rows import FRAME_COLUMNS, FRAME_OWN_COLUMNS, FrameAligner, FrameRecord, TelemetrySample
from uav_values.camera import CameraModel, Mount

GOAL_P95_M = {20.0: 1.0, 50.0: 2.0}
"""Issue 39's goals for the simulator's perfect attitude."""


def fly_over_car(height: float, *, tilt: float, attitude_deg: float, count: int, seed: int) -> np.ndarray:
    """(error m, stated uncertainty m) of ``count`` views of a parked car from random poses at ``height``."""
    results = []
    for view in car_views(height, tilt=tilt, attitude_deg=attitude_deg, count=count, seed=seed):
        fix = view.locate()
        assert fix.status == geolocate.OK, view
        n, e, d = HOME.to_local(fix.lat_deg, fix.lon_deg, fix.alt_m)
        assert d == pytest.approx(0.0, abs=1e-6)  # the ground's altitude: home's
        assert fix.distance_m == pytest.approx(math.hypot(n - view.pose.n, e - view.pose.e), abs=1e-3)
        results.append((view.error_m(fix), fix.uncertainty_m))
    return np.array(results)


@pytest.mark.parametrize("height", [20.0, 50.0])
@pytest.mark.parametrize("tilt, attitude_deg", [(90.0, 0.0), (90.0, 15.0), (60.0, 15.0)],
                         ids=["down-level", "down-rolling-pitching", "oblique-rolling-pitching"])
def test_a_car_in_the_simulator_is_located_within_the_stated_uncertainty(height, tilt, attitude_deg):
    found = fly_over_car(height, tilt=tilt, attitude_deg=attitude_deg, count=25, seed=int(height + tilt + attitude_deg))
    errors, uncertainty = found[:, 0], found[:, 1]
    assert np.all(errors <= uncertainty), found
    assert np.percentile(errors, 95) <= GOAL_P95_M[height]
    assert np.all(uncertainty < 0.1 * height)  # 1-2 deg and 0.5 m: about 2-6 % of the height at these views


def test_the_uncertainty_is_what_the_stated_errors_move_the_point():
    model = CameraModel.from_hfov(640, 480, 62.0, Mount(90.0))
    centre = (320, 240, 1, 1)  # straight down: roll and pitch move the point by h tan(1 deg), yaw and height not
    fix = geolocate.locate(model, centre, roll_deg=0, pitch_deg=0, yaw_deg=0, lat_deg=0, lon_deg=0, height_m=20)
    assert fix.uncertainty_m == pytest.approx(math.sqrt(2) * 20 * math.tan(math.radians(1.0)), rel=1e-3)
    assert (fix.north_m, fix.east_m, fix.alt_m) == (pytest.approx(0.0), pytest.approx(0.0), None)


def test_a_box_at_or_above_the_horizon_has_no_position():
    forward = CameraModel.from_hfov(640, 480, 62.0, Mount(0.0))
    pose = dict(roll_deg=0.0, pitch_deg=0.0, yaw_deg=0.0, lat_deg=47.0, lon_deg=8.0, height_m=20.0)
    for row in (0, 240, 245):  # above, on and just below the horizon (less than MIN_DEPRESSION_DEG)
        fix = geolocate.locate(forward, (300, row, 10, 1), **pose)
        assert (fix.status, fix.lat_deg, fix.uncertainty_m, fix.distance_m) == (geolocate.HORIZON, None, None, None)
    assert geolocate.locate(forward, (300, 470, 10, 10), **pose).status == geolocate.OK
    # Pitched up 40 degrees, even the bottom of the forward camera's picture is sky.
    tilted = {**pose, "pitch_deg": 40.0}
    assert geolocate.locate(forward, (300, 470, 10, 10), **tilted).status == geolocate.HORIZON


@pytest.mark.parametrize("missing, status", [
    ("camera", geolocate.NO_CAMERA), ("lat_deg", geolocate.NO_POSITION), ("lon_deg", geolocate.NO_POSITION),
    ("yaw_deg", geolocate.NO_ATTITUDE), ("height_m", geolocate.NO_HEIGHT), ("box", geolocate.NO_BOX)])
def test_missing_input_gives_a_status_and_no_position(missing, status):
    inputs = dict(camera=CameraModel.from_hfov(640, 480, 62.0), box=(300, 200, 20, 20), roll_deg=0.0, pitch_deg=0.0,
                  yaw_deg=0.0, lat_deg=47.0, lon_deg=8.0, height_m=20.0, abs_alt_m=500.0)
    fix = geolocate.locate(**{**inputs, missing: None})
    assert (fix.status, fix.lat_deg, fix.lon_deg, fix.alt_m, fix.uncertainty_m) == (status, None, None, None, None)
    nan = geolocate.locate(**{**inputs, missing: math.nan}) if missing not in ("camera", "box") else fix
    assert nan.status == status


def test_a_rangefinder_height_is_preferred_tilt_corrected_and_said():
    camera = CameraModel.from_hfov(640, 480, 62.0)
    box = (400, 300, 20, 20)
    # rolled 10 degrees, 20 m over the ground: the rangefinder reads along the tilted down axis; the barometer
    # says 23 m above home (the ground here is 3 m lower than home, or the barometer drifted)
    pose = dict(roll_deg=10.0, pitch_deg=-4.0, yaw_deg=30.0, lat_deg=47.0, lon_deg=8.0, abs_alt_m=523.0)
    reading = 20.0 / (math.cos(math.radians(10.0)) * math.cos(math.radians(-4.0)))
    fix = geolocate.locate_row(camera, box, {**pose, "rel_alt_m": 23.0, "rangefinder_m": reading})
    truth = geolocate.locate(camera, box, **pose, height_m=20.0)
    assert (fix.lat_deg, fix.lon_deg, fix.height_m) == (pytest.approx(truth.lat_deg, abs=1e-9),
                                                        pytest.approx(truth.lon_deg, abs=1e-9), pytest.approx(20.0))
    assert fix.height_from == geolocate.FROM_RANGEFINDER and fix.alt_m == pytest.approx(503.0)
    assert fix.uncertainty_m < truth.uncertainty_m  # 0.1 m of height error assumed instead of 0.5 m
    # out of its range (None) or without one: the height above home, said so
    for telemetry in ({**pose, "rel_alt_m": 23.0, "rangefinder_m": None}, {**pose, "rel_alt_m": 23.0}):
        fallback = geolocate.locate_row(camera, box, telemetry)
        assert fallback.height_from == geolocate.FROM_HOME and fallback.height_m == 23.0
        assert fallback.lat_deg == geolocate.locate(camera, box, **pose, height_m=23.0).lat_deg


def test_a_downward_rangefinder_reading_reaches_telemetry_only_in_range():
    def sensor(current: float, pitch: float = 270.0) -> SimpleNamespace:
        return SimpleNamespace(minimum_distance_m=0.05, maximum_distance_m=40.0, current_distance_m=current,
                               orientation=SimpleNamespace(roll_deg=0.0, pitch_deg=pitch, yaw_deg=0.0))

    assert from_distance_sensor(sensor(12.5)) == {"rangefinder_m": 12.5}
    assert from_distance_sensor(sensor(12.5, pitch=-90.0)) == {"rangefinder_m": 12.5}
    for out_of_range in (40.01, 0.0, math.nan):
        assert from_distance_sensor(sensor(out_of_range)) == {"rangefinder_m": None}
    assert from_distance_sensor(sensor(12.5, pitch=0.0)) == {}  # a forward obstacle sensor is not a height


def test_a_position_of_0_0_before_the_first_fix_is_no_position():
    def position(lat: float, lon: float) -> SimpleNamespace:
        return SimpleNamespace(latitude_deg=lat, longitude_deg=lon, absolute_altitude_m=0.0, relative_altitude_m=0.0)

    assert from_position(position(0.0, 0.0))["lat_deg"] is None  # ArduPilot's GLOBAL_POSITION_INT before a fix
    assert from_position(position(0.0, 0.0))["lon_deg"] is None
    assert from_position(position(0.0, 8.5)) == {"lat_deg": 0.0, "lon_deg": 8.5, "abs_alt_m": 0.0, "rel_alt_m": 0.0}


def _row(camera: CameraModel | None, telemetry: Telemetry) -> dict:
    aligner = FrameAligner(hold_ns=0, min_hold_ns=0)
    aligner.handle(TelemetrySample(telemetry, 0))
    values = [1, *[None] * (FRAME_OWN_COLUMNS.index("telemetry") - 1)]  # up to extra: the aligner adds the rest
    values[FRAME_OWN_COLUMNS.index("box_x"):FRAME_OWN_COLUMNS.index("box_x") + 4] = [310, 230, 20, 20]
    aligner.handle(FrameRecord(values, 0, camera))
    return dict(zip(FRAME_COLUMNS, aligner.drain()[0].values, strict=True))


def test_a_frame_row_holds_the_target_position_or_why_there_is_none():
    camera = CameraModel.from_hfov(640, 480, 62.0)
    flying = Telemetry(lat_deg=47.0, lon_deg=8.0, abs_alt_m=520.0, rel_alt_m=20.0, roll_deg=0.0, pitch_deg=0.0,
                       yaw_deg=90.0)
    row = _row(camera, flying)
    assert row["target_status"] == "ok" and row["target_height_from"] == "home"
    assert row["target_lat_deg"] == pytest.approx(47.0, abs=1e-6) and row["target_alt_m"] == pytest.approx(500.0)
    assert 0.3 < row["target_uncertainty_m"] < 1.0
    no_gps = _row(camera, Telemetry(rel_alt_m=20.0, roll_deg=0.0, pitch_deg=0.0, yaw_deg=0.0))
    no_camera = _row(None, flying)
    for row, status in ((no_gps, "no_position"), (no_camera, "no_camera")):
        assert row["target_status"] == status
        assert [row[c] for c in ("target_lat_deg", "target_lon_deg", "target_alt_m", "target_uncertainty_m")] \
            == [None] * 4


def test_a_distorted_camera_mounted_off_centre_locates_the_ground_point_its_pixel_shows():
    ideal = CameraModel.from_hfov(640, 480, 70.0)
    model = CameraModel(640, 480, ideal.fx, ideal.fy, ideal.cx, ideal.cy, (-0.28, 0.09, 0.0008, -0.0005, 0.0),
                        Mount(60.0, (0.3, 0.0, 0.1)))
    # Level, heading east, 20 m up: the camera sits 0.3 m east of the vehicle and 0.1 m lower, looking east,
    # 60 deg below the horizon, so its optical axis meets the ground at (19.9 / tan 60) m east of it.
    ahead = 0.3 + 19.9 / math.tan(math.radians(60.0))
    u, v = model.ray_to_pixel(np.array([0.0, 0.0, 1.0]))
    fix = geolocate.locate(model, (u - 4.5, v - 4.5, 10, 10), roll_deg=0.0, pitch_deg=0.0, yaw_deg=90.0, lat_deg=0.0,
                           lon_deg=0.0, height_m=20.0)
    assert (fix.north_m, fix.east_m) == (pytest.approx(0.0, abs=1e-6), pytest.approx(ahead, abs=1e-6))
    # Off the axis, through the distortion: the pixel where a ground point shows is located back onto it.
    seen = np.array([8.0, -5.0, 19.9])  # a ground point from the camera, FRD (the vehicle heads north here)
    pixel = model.ray_to_pixel(model.rotation_body_camera.T @ seen)  # the vehicle sees it 0.3 m further ahead
    fix = geolocate.locate(model, (pixel[0] - 4.5, pixel[1] - 4.5, 10, 10), roll_deg=0.0, pitch_deg=0.0, yaw_deg=0.0,
                           lat_deg=0.0, lon_deg=0.0, height_m=20.0)
    assert (fix.north_m, fix.east_m) == (pytest.approx(8.3, abs=1e-4), pytest.approx(-5.0, abs=1e-4))


def test_the_status_line_says_where_or_why_not():
    fix = geolocate.GeoFix(geolocate.OK, 47.3977961, 8.5456, 488.0, 0.62, north_m=6.0, east_m=-0.1)
    assert geolocate.describe(fix) == "47.397796,8.545600 6 m at 359 deg +-0.6 m"
    assert geolocate.describe(geolocate.GeoFix(geolocate.HORIZON)) == "not located: at or above the horizon"
    assert geolocate.describe(geolocate.GeoFix(geolocate.NO_POSITION)) == "not located: no GPS position"
    assert geolocate.describe(geolocate.GeoFix(geolocate.NO_CAMERA)) == ""  # the event log said it once
    assert geolocate.describe(geolocate.GeoFix(geolocate.NO_BOX)) == ""


def test_a_bearing_a_hair_west_of_north_reads_000_not_360():
    fix = geolocate.GeoFix(geolocate.OK, 47.0, 8.0, 488.0, 0.8, 6.0, -0.04, 20.0, geolocate.FROM_HOME)
    assert fix.bearing_deg > 359.5 and " 6 m at 000 deg " in geolocate.describe(fix)


@pytest.mark.parametrize("impossible, status", [
    ({"lat_deg": 91.0}, geolocate.NO_POSITION), ({"lon_deg": 200.0}, geolocate.NO_POSITION),
    ({"height_m": -10.0}, geolocate.NO_HEIGHT), ({"height_m": 1e7}, geolocate.NO_HEIGHT),
    ({"height_m": math.inf}, geolocate.NO_HEIGHT), ({"roll_deg": 1e6}, geolocate.NO_ATTITUDE)],
    ids=["lat-91", "lon-200", "height-minus-10", "height-10000-km", "height-inf", "roll-1e6"])
def test_telemetry_that_cannot_be_true_gives_no_position(impossible, status):
    """A recording's telemetry is checked here too (an edited telemetry.csv never met the vehicle's boundary)."""
    inputs = dict(camera=CameraModel.from_hfov(640, 480, 62.0), box=(300, 200, 20, 20), roll_deg=0.0, pitch_deg=0.0,
                  yaw_deg=0.0, lat_deg=47.0, lon_deg=8.0, height_m=20.0, abs_alt_m=500.0)
    assert geolocate.locate(**{**inputs, **impossible}).status == status
    assert geolocate.locate(**{**inputs, "abs_alt_m": math.inf}).alt_m is None
