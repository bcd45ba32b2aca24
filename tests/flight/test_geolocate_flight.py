"""A recorded flight of the built-in simulator over its car: frames.csv places the car where the simulator has it."""

from __future__ import annotations

import asyncio
import json
import math
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from tests.core.flight_helpers import flying_core
from uav_tui.flight.geolocate import OK, RANGEFINDER_SIGMA_M
from uav_tui.headless import format_status
from uav_tui.recorded import dataset, runs_cli
from uav_tui.recording.rows import GEO_COLUMNS

ALTITUDE_M = 20.0
GOAL_P95_M = 1.0
"""Issue 39's goal at 20 m with the simulator's perfect attitude (the telemetry is interpolated to each capture)."""


async def test_a_recorded_flight_locates_the_car_it_sees(tmp_path):
    source = "sim:?fps=15&targets=1&target_speed=0"  # a parked car 6 m north of home
    async with flying_core(tmp_path, altitude=ALTITUDE_M, source=source, record=True, runs_dir=str(tmp_path),
                           max_speed=2.0, processor="tests.recording.recorder_processors:RedCar") as core:
        car_n, car_e, _ = core.source.targets[0].position(0.0)
        home = core.controller.sim.home
        for command in ("vector 0 2 3", "vector 0 -2 3"):  # sideways at 2 m/s: it rolls, then flies level
            await core.execute(command)
            await asyncio.sleep(3.5)
        status = core.status()  # hovering again, 6 m south of the car: the status line says where it is
        line = format_status(status, 0.0)
        run_dir = core.recorder.run_dir
    frames = dataset.load(run_dir).frames
    vehicle_n, vehicle_e = status.telemetry.north_m, status.telemetry.east_m
    assert status.target is not None and status.target.status == OK
    assert status.target.distance_m == pytest.approx(math.hypot(car_n - vehicle_n, car_e - vehicle_e), abs=0.5)
    # the car is north, a little either side as the vehicle ends its flight over home (0.9 m east under load)
    bearing = math.degrees(math.atan2(car_e - vehicle_e, car_n - vehicle_n)) % 360
    shown = re.search(r" \| target 47\.\d+,8\.\d+ \d+ m at (\d{3}) deg ", line)
    assert shown, line
    assert abs((float(shown.group(1)) - bearing + 180) % 360 - 180) <= 5, (line, bearing)  # 0.3 m at 6 m: 3 deg
    as_json = json.loads(json.dumps(status.as_dict(), default=str))["target"]  # --json lines, the web page
    assert as_json["status"] == OK and as_json["distance_m"] == pytest.approx(status.target.distance_m)
    assert set(GEO_COLUMNS) <= set(frames.columns)
    whole = (frames["box_x"] > 0) & (frames["box_y"] > 0) & (frames["box_x"] + frames["box_w"] < 640) \
        & (frames["box_y"] + frames["box_h"] < 480)  # a car cut by the frame's edge is not centred in its box
    located = frames[(frames["target_status"] == OK) & (frames["telemetry"] == "interpolated") & whole]
    assert len(located) >= 60, frames["target_status"].value_counts()  # the 6 s flown at 15 fps: ~90
    n, e, alt = zip(*(home.to_local(*row) for row in located[["target_lat_deg", "target_lon_deg", "target_alt_m"]]
                      .to_numpy(dtype=np.float64)), strict=True)
    errors = np.hypot(np.array(n) - car_n, np.array(e) - car_e)
    # The ground is home's altitude, to millimetres, except on the frames drawn while the simulator tilts within
    # one tick (the range, read along the body's axis, and the attitude that corrects it are then from different
    # instants): most within the rangefinder's assumed 1-sigma, all within 3. How many such frames there are is the
    # machine's load: at load 5-20, p95 0.115-0.158 m and max 0.24-0.29 m were seen (the test passed alone).
    heights = np.abs(alt)
    assert np.median(heights) <= 0.01 and np.mean(heights <= RANGEFINDER_SIGMA_M) >= 0.9 \
        and heights.max() <= 3 * RANGEFINDER_SIGMA_M, np.percentile(heights, [50, 90, 95, 100])
    assert np.percentile(errors, 95) <= GOAL_P95_M, np.percentile(errors, [50, 95, 100])
    # The simulator tilts within one tick when a vector starts, between two 10 Hz attitude samples: the frame or
    # two drawn then are off by up to ~1 m, the rest by centimetres.
    # Under load (2 cores, 5 sessions) the simulator's ticks are irregular: up to 7 % of the frames measured.
    assert np.mean(errors <= located["target_uncertainty_m"].to_numpy(dtype=np.float64)) >= 0.9
    moving = np.hypot(located["vn_ms"], located["ve_ms"]).to_numpy(dtype=np.float64) > 1.5
    tilted = np.hypot(located["roll_deg"], located["pitch_deg"]).to_numpy(dtype=np.float64) > 3.0
    assert moving.sum() > 10 and tilted.sum() > 3, "the flight must include fast and tilted frames to mean anything"
    assert math.isclose(located["rel_alt_m"].median(), ALTITUDE_M, abs_tol=1.0)
    # the simulator's downward rangefinder (40 m range) gave the height, along the tilted body axis
    assert (located["target_height_from"] == "rangefinder").all()
    assert (located["rangefinder_m"] >= located["rel_alt_m"] - 0.1).all()
    assert (located.loc[tilted, "rangefinder_m"] > located.loc[tilted, "rel_alt_m"] + 0.01).any()

    # Exported for QGIS and Google Earth: both parse and hold the recorded positions and the track.
    assert runs_cli.main("export", [str(run_dir)]) == 0
    features = json.loads((run_dir / "track.geojson").read_text())["features"]
    points = [f for f in features if f["properties"]["kind"] == "target"]
    recorded = frames[frames["target_status"] == OK]
    assert [p["properties"]["frame_id"] for p in points] == recorded["frame_id"].tolist()
    assert np.allclose([p["geometry"]["coordinates"][:2] for p in points],
                       recorded[["target_lon_deg", "target_lat_deg"]].to_numpy(dtype=np.float64), atol=1e-8)
    track = [f for f in features if f["geometry"]["type"] == "LineString"]
    assert len(track) == 1 and len(track[0]["geometry"]["coordinates"]) == len(track[0]["properties"]["times"]) > 50
    kml = ET.parse(run_dir / "track.kml").getroot()
    ns = {"k": "http://www.opengis.net/kml/2.2"}
    placemarks = kml.findall("k:Document/k:Placemark/k:Point/k:coordinates", ns)
    assert len(placemarks) == len(points)
    lon, lat = (float(v) for v in placemarks[0].text.split(","))
    assert (lon, lat) == (pytest.approx(points[0]["geometry"]["coordinates"][0], abs=1e-8),
                          pytest.approx(points[0]["geometry"]["coordinates"][1], abs=1e-8))
    assert len(kml.findall("k:Document/k:Placemark/k:TimeStamp/k:when", ns)) == len(points)
