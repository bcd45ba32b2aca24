"""A recorded flight of the built-in simulator over its car: frames.csv places the car where the simulator has it."""

from __future__ import annotations

import json
import math
import re
import xml.etree.ElementTree as ET

import numpy as np
import pandas as pd
import pytest

from tests.flight.car_flight import GOALS_P95_M, STILL_MS, fly_over_the_car
from uav_tui.flight.geolocate import OK, RANGEFINDER_SIGMA_M
from uav_tui.headless import format_status
from uav_tui.recorded import runs_cli
from uav_tui.recording.rows import GEO_COLUMNS


@pytest.mark.parametrize(("altitude", "height_from"), [(20.0, "rangefinder"), (50.0, "terrain")])
async def test_a_recorded_flight_locates_the_car_it_sees(tmp_path, altitude, height_from):
    """The height comes from the simulator's downward rangefinder up to its 40 m, above from PX4's height above the
    terrain (ALTITUDE's bottom clearance)."""
    flight = await fly_over_the_car(tmp_path, altitude, hover_s=1.0)
    status, frames, located, errors = flight.status, flight.frames, flight.located, flight.errors
    car_n, car_e = flight.car_ne
    line = format_status(status, 0.0)  # hovering again, 6 m south of the car: the status line says where it is
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
    # the climb, 1 s hovering, 7 s flown at 15 fps: over 60 quiet, 57 when a loaded machine starved the renderer
    assert len(located) >= 40, frames["target_status"].value_counts()
    # The ground is home's altitude, to millimetres, except on the frames drawn while the simulator tilts within
    # one tick (the range, read along the body's axis, and the attitude that corrects it are then from different
    # instants): most within the rangefinder's assumed 1-sigma. How many such frames there are is the
    # machine's load: at load 5-20, p95 0.115-0.158 m and max 0.24-0.29 m were seen at 20 m (0.05 m at 50 m, load 1).
    # Not while climbing (see the range's check below): at 5 m/s a reading a loaded loop stamped 0.1 s late is 0.5 m
    # off; with those frames, 15 % were outside the 1-sigma at load 20.
    level = np.abs(located["vd_ms"]).to_numpy(dtype=np.float64) < STILL_MS
    heights = np.abs(flight.ground_m[level])
    # No bound on the worst frame: it is the one drawn nearest a tilt, as late as the load makes it (0.40 m, load 12).
    assert np.median(heights) <= 0.01 and np.mean(heights <= RANGEFINDER_SIGMA_M) >= 0.9, \
        np.percentile(heights, [50, 90, 95, 100])
    # Issue 39's p95 goals are scripts/bench_geolocation.py's figures: a p95 here counts the frames a loaded machine
    # drew between two telemetry samples as the vehicle tilted (1.18 m at 20 m, load 20; 3.7 m the worst frame). The
    # median is the geolocation's, whatever the load.
    assert np.median(errors) <= GOALS_P95_M[altitude] / 4, np.percentile(errors, [50, 95, 100])
    # The simulator tilts within one 20 ms tick when a vector starts: a frame drawn then is off by up to ~1 m (20 m)
    # or 3 m (50 m: 1 of 243 frames), the rest by centimetres. Under load (2 cores, 5 sessions) the simulator's ticks
    # are irregular: up to 7 % of the frames measured at 20 m.
    assert np.mean(flight.within_stated()) >= 0.9
    hovering, fast = flight.hovering(), flight.fast()
    # hovering: 0.04 m at 20 m, 0.06 m at 50 m (p95, quiet machine); flying 2 m/s: 0.17 m and 0.38 m
    assert np.percentile(errors[hovering], 95) <= GOALS_P95_M[altitude] / 4, np.percentile(errors[hovering], [50, 95])
    assert np.median(errors[fast]) <= GOALS_P95_M[altitude] / 4, np.percentile(errors[fast], [50, 95])
    tilted = np.hypot(located["roll_deg"], located["pitch_deg"]).to_numpy(dtype=np.float64) > 3.0
    assert hovering.sum() > 5 and fast.sum() > 10 and tilted.sum() > 3, \
        "the flight must include hovering, fast and tilted frames to mean anything"
    assert math.isclose(located["rel_alt_m"].median(), altitude, abs_tol=1.0)
    low, high = located["rel_alt_m"] < 39.0, located["rel_alt_m"] > 41.0  # the rangefinder's 40 m, either side
    # Below 40 m the rangefinder, above it the terrain height, unless that reading was too old at the capture (a
    # loaded machine's late loop): then the frame says so, and which reading it used instead.
    def used_or_said(source: str) -> pd.Series:
        return (located["target_height_from"] == source) | \
            located["target_height_note"].fillna("").str.contains(rf"{source} \d+\.\d s old")
    for band, source in ((low, "rangefinder"), (high, "terrain")):
        said = used_or_said(source)
        assert said[band].all(), located.loc[band & ~said, ["target_height_from", "target_height_note"]]
        assert not band.any() or (located.loc[band, "target_height_from"] == source).mean() >= 0.5  # most
    assert used_or_said(height_from)[hovering | fast].all()
    # Along the tilted body axis: never shorter than the height. Not while climbing: the range and the altitude are
    # stamped as each arrives, and at the climb's 5 m/s a reading 0.1 s later than the altitude (a loaded loop) is
    # 0.5 m apart; at under STILL_MS the loop may be 0.5 s late before 0.1 m.
    ranged = located[low & level]
    assert (ranged["rangefinder_m"] >= ranged["rel_alt_m"] - 0.1).all()
    if height_from == "rangefinder":
        assert len(ranged) > 10, "the flight must range level frames to mean anything"
        assert (located.loc[tilted, "rangefinder_m"] > located.loc[tilted, "rel_alt_m"] + 0.01).any()
    run_dir = flight.run_dir

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
