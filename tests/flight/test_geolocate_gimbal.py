"""A camera on the gimbal: the sim: camera draws along the gimbal's attitude, and geo-location uses that attitude,
not the vehicle's."""

from __future__ import annotations

import math

import pytest

from controllers.sim.geo import Home
from sources import create_source
from sources.pose import PoseAt
from sources.sim_geometry import Pose, project_ground_point
from uav_tui.flight import geolocate
from uav_values.camera import Mount

VEHICLE = Pose(n=4.0, e=-3.0, d=-20.0, roll=8.0, pitch=-6.0, yaw=30.0)
GIMBAL = (0.0, -55.0, 25.0)
"""Roll and pitch from the horizon, yaw from the nose: the camera looks 55 degrees down, 55 degrees east of north."""


def test_the_sim_camera_on_the_gimbal_looks_with_the_gimbal_and_says_so() -> None:
    source = create_source("sim:?width=64&height=48&fps=100&mount=gimbal",
                           pose_provider=lambda t: PoseAt(VEHICLE, 0.0, GIMBAL))
    assert source.camera_model().mount == Mount(0.0, gimbal=True)
    assert source.open()
    try:
        assert source.buffer.wait_newer(0, 30) is not None  # the ground texture is built first: seconds when loaded
        pose = source.get_properties()["pose"]
    finally:
        source.close()
    assert pose == {"n": 4.0, "e": -3.0, "d": -20.0, "roll": 0.0, "pitch": -55.0, "yaw": 55.0}


def test_a_box_seen_through_the_gimbal_is_located_with_the_gimbal_s_attitude() -> None:
    source = create_source("sim:?width=640&height=480&mount=gimbal")
    camera, model = source.camera, source.camera_model()
    looking = Pose(VEHICLE.n, VEHICLE.e, VEHICLE.d, GIMBAL[0], GIMBAL[1], VEHICLE.yaw + GIMBAL[2])
    car = (VEHICLE.n + 10.0, VEHICLE.e + 12.0)
    u, v = project_ground_point(*car, looking, camera)  # type: ignore[misc]
    box = (u - 10 + 0.5, v - 10 + 0.5, 20, 20)  # centred on the car (OpenCV's pixel centres)
    home = Home()
    lat, lon, _ = home.to_global(VEHICLE.n, VEHICLE.e, VEHICLE.d)
    telemetry = {"lat_deg": lat, "lon_deg": lon, "rel_alt_m": 20.0, "roll_deg": VEHICLE.roll,
                 "pitch_deg": VEHICLE.pitch, "yaw_deg": VEHICLE.yaw, "gimbal_roll_deg": GIMBAL[0],
                 "gimbal_pitch_deg": GIMBAL[1], "gimbal_yaw_deg": VEHICLE.yaw + GIMBAL[2]}
    fix = geolocate.locate_row(model, box, telemetry)
    assert fix.status == geolocate.OK
    n, e, _ = home.to_local(fix.lat_deg, fix.lon_deg, 0.0)  # type: ignore[arg-type]
    assert math.hypot(n - car[0], e - car[1]) < 0.05
    without = geolocate.locate_row(model, box, {k: v for k, v in telemetry.items() if not k.startswith("gimbal")})
    assert without.status == geolocate.NO_ATTITUDE  # on the gimbal, the vehicle's attitude is not the camera's
    fixed = geolocate.locate_row(source.__class__("sim:").camera_model(), box, telemetry)  # a camera fixed down
    n, e, _ = home.to_local(fixed.lat_deg, fixed.lon_deg, 0.0)  # type: ignore[arg-type]
    assert math.hypot(n - car[0], e - car[1]) > 5  # the vehicle's attitude would put it elsewhere


@pytest.mark.parametrize("mount", ["gimbal", "GIMBAL "])
def test_the_gimbal_mount_parses(mount: str) -> None:
    assert Mount.parse(mount) == Mount(0.0, (0.0, 0.0, 0.0), True)
    assert Mount.parse(mount).describe() == "gimbal"
