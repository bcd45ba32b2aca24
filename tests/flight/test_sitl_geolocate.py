"""Geo-location on real PX4 SIH and ArduCopter SITL: the sim: camera's parked car, located from 20 m.

The sim: camera draws the world from the autopilot's own pose (its local origin is the world's), so the car
stands 6 m north of the autopilot's local origin. Each located frame's target, put in local metres through
the frame's own position (north_m/east_m, lat/lon), must land on it: the autopilot's real attitude,
altitude and timing go through the projection, while it hovers and while it flies sideways; the height above
the ground is PX4 SIH's simulated rangefinder's, ArduCopter's height above home.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from collections.abc import Callable
from contextlib import AbstractContextManager
from pathlib import Path

import numpy as np
import pytest

from sources.sim_render import default_targets
from tests import sitl
from uav_tui.flight.geolocate import EARTH_RADIUS_M, FROM_HOME, FROM_RANGEFINDER, OK
from uav_tui.recorded import dataset

pytestmark = pytest.mark.sitl

ROOT = Path(__file__).resolve().parents[2]
ALTITUDE_M = 20.0
GOAL_P95_M = 1.0
"""Issue 39's goal at 20 m (the built-in simulator's: a real autopilot's estimate must not add to it here)."""

SCRIPT = """arm
takeoff 20
wait 25
vector 0 1 3
wait 4
vector 0 -1 3
wait 4
"""
"""Climb to 20 m (PX4 ~1.5 m/s after spin-up), hover, then sideways and back: it rolls both ways."""


def fly(fc: str, tmp_path: Path, wait_first_s: float) -> dataset.Dataset:
    script = tmp_path / "geo.txt"
    script.write_text(f"wait {wait_first_s:g}\n{SCRIPT}")
    result = subprocess.run(
        [sys.executable, "-m", "uav_tui", "--no-ui", "--fc", fc, "--source", "sim:?fps=15&targets=1&target_speed=0",
         "--processor", "tests.recording.recorder_processors:RedCar", "--script", str(script),
         "--runs-dir", str(tmp_path / "runs")],
        cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    return dataset.load(next((tmp_path / "runs").iterdir()))


@pytest.mark.timeout(400)
@pytest.mark.parametrize("launch, height_from", [(sitl.px4_sih, FROM_RANGEFINDER), (sitl.arducopter, FROM_HOME)],
                         ids=["px4_sih", "arducopter"])
def test_the_parked_car_is_located_where_it_stands_on_a_real_autopilot(
        launch: Callable[[Path], AbstractContextManager[sitl.Sitl]], height_from: str, tmp_path: Path) -> None:
    """SIH simulates a downward distance sensor, which PX4 sends as DISTANCE_SENSOR; ArduCopter's SITL has none
    unless its RNGFND1_* parameters configure one: there the height above home is used."""
    workdir = tmp_path / "sitl"
    workdir.mkdir()
    with launch(workdir) as vehicle:
        try:
            run = fly(vehicle.connection_string, tmp_path, vehicle.ready_after_s)
        except AssertionError as exc:
            raise AssertionError(f"{exc}\n--- {vehicle.name} log ---\n{vehicle.log_tail()}") from None
    car_n, car_e, _ = default_targets(1, 0.0)[0].position(0.0)
    frames = run.frames
    whole = (frames["box_x"] > 0) & (frames["box_y"] > 0) & (frames["box_x"] + frames["box_w"] < 640) \
        & (frames["box_y"] + frames["box_h"] < 480)  # a car cut by the frame's edge is not centred in its box
    high = frames["rel_alt_m"] > ALTITUDE_M - 1.0
    located = frames[(frames["target_status"] == OK) & (frames["telemetry"] == "interpolated") & whole & high]
    assert len(located) >= 100, frames["target_status"].value_counts()  # ~20 s at 20 m, 15 fps
    columns = ["north_m", "east_m", "lat_deg", "lon_deg", "target_lat_deg", "target_lon_deg"]
    n, e, lat, lon, target_lat, target_lon = located[columns].to_numpy(dtype=np.float64).T
    target_n = n + np.radians(target_lat - lat) * EARTH_RADIUS_M
    target_e = e + np.radians(target_lon - lon) * EARTH_RADIUS_M * np.cos(np.radians(lat))
    errors = np.hypot(target_n - car_n, target_e - car_e)
    assert np.percentile(errors, 95) <= GOAL_P95_M, np.percentile(errors, [50, 95, 100])
    assert np.mean(errors <= located["target_uncertainty_m"].to_numpy(dtype=np.float64)) >= 0.9
    tilted = np.hypot(located["roll_deg"], located["pitch_deg"]).to_numpy(dtype=np.float64) > 2.0
    assert tilted.sum() > 3, "the flight must include tilted frames to mean anything"
    assert math.isclose(located["rel_alt_m"].median(), ALTITUDE_M, abs_tol=1.0)
    # A reading that stopped for over READING_MAX_AGE_S (the telemetry stalled: 2 cores under load) is refused, said:
    # seen once with PX4 SIH under load. Otherwise the source this autopilot has.
    other = located[located["target_height_from"] != height_from]
    assert len(other) <= 0.1 * len(located), other["target_height_from"].value_counts()
    assert other["target_height_note"].fillna("").str.contains(r"^(?:rangefinder|terrain) \d", regex=True).all()
