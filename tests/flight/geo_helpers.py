"""Views of the built-in simulator's car from known poses (test_geolocate.py, scripts/bench_geolocation.py)."""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from controllers.sim.geo import Home
from sources.ground import default_ground
from sources.sim_camera import SimCameraSource
from sources.sim_geometry import PinholeCamera, Pose
from sources.sim_render import GroundTarget, SimRenderer
from uav_tui.flight import geolocate
from uav_values.camera import CameraModel

HOME = Home()


@dataclass(frozen=True)
class CarView:
    """The sim: camera's exact model, the vehicle's pose, the parked car and its box in the rendered frame."""

    model: CameraModel
    pose: Pose
    car: GroundTarget
    box: tuple[int, int, int, int]

    def locate(self, *, attitude_error_deg: float = 0.0, height_error_m: float = 0.0) -> geolocate.GeoFix:
        """Geo-locate the box from the true pose, roll and pitch off by ``attitude_error_deg``, height by the other."""
        p = self.pose
        lat, lon, alt = HOME.to_global(p.n, p.e, p.d)
        return geolocate.locate(self.model, self.box, roll_deg=p.roll + attitude_error_deg,
                                pitch_deg=p.pitch + attitude_error_deg, yaw_deg=p.yaw, lat_deg=lat, lon_deg=lon,
                                height_m=-p.d + height_error_m, abs_alt_m=alt)

    def error_m(self, fix: geolocate.GeoFix) -> float:
        """Horizontal distance between ``fix`` and the car's true position."""
        assert fix.lat_deg is not None and fix.lon_deg is not None
        n, e, _ = HOME.to_local(fix.lat_deg, fix.lon_deg, 0.0)
        return math.hypot(n - self.car.centre_n, e - self.car.centre_e)


def car_box(renderer: SimRenderer, pose: Pose, index: int) -> tuple[int, int, int, int] | None:
    """The rendered car's bounding box: the pixels that differ from the same frame drawn without it."""
    with_car = renderer.render(pose, 0.0, index)
    cars, renderer.targets = renderer.targets, []
    without = renderer.render(pose, 0.0, index)
    renderer.targets = cars
    ys, xs = np.nonzero(np.any(with_car != without, axis=2))
    if len(xs) == 0 or xs.min() == 0 or ys.min() == 0 or xs.max() == with_car.shape[1] - 1 \
            or ys.max() == with_car.shape[0] - 1:
        return None  # not wholly in view
    return int(xs.min()), int(ys.min()), int(xs.max() - xs.min() + 1), int(ys.max() - ys.min() + 1)


def car_views(height: float, *, tilt: float, attitude_deg: float, count: int, seed: int) -> Iterator[CarView]:
    """``count`` views of a parked car wholly in the frame, from random poses at ``height`` (roll and pitch
    within +-``attitude_deg``, any heading), the camera ``tilt`` degrees below the nose."""
    camera = PinholeCamera(640, 480, 62.0, tilt)
    model = SimCameraSource(camera=camera).camera_model()
    rng = np.random.default_rng(seed)
    renderer = SimRenderer(camera, default_ground(0), noise_sigma=2.0)
    found = 0
    while found < count:
        roll, pitch = rng.uniform(-attitude_deg, attitude_deg, 2)
        pose = Pose(rng.uniform(-50, 50), rng.uniform(-50, 50), -height, roll, pitch, rng.uniform(-180, 180))
        reach = height * (0.6 if tilt == 90 else 1.2)
        car = GroundTarget(pose.n + rng.uniform(-reach, reach), pose.e + rng.uniform(-reach, reach), 0.0, 0.0,
                           phase=rng.uniform(0, 2 * math.pi))
        renderer.targets = [car]
        box = car_box(renderer, pose, found)
        if box is not None:
            found += 1
            yield CarView(model, pose, car, box)
