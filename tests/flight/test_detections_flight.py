"""A processor's ``detections`` over the built-in simulator's two cars: each located, tracked, recorded, shown and
exported; malformed ones are the processor's error and nothing of them is recorded."""

from __future__ import annotations

import asyncio
import json
import math
import xml.etree.ElementTree as ET

import numpy as np

from tests.core.flight_helpers import flying_core
from uav_tui.flight.geolocate import OK
from uav_tui.headless import format_status
from uav_tui.recorded import dataset, runs_cli
from uav_tui.recording.located import DETECTION_COLUMNS

ALTITUDE_M = 30.0
"""High enough that the down camera sees both cars (6 m north of home, and 12 m away to the south-east)."""


async def test_each_detection_is_located_recorded_shown_and_exported(tmp_path):
    source = "sim:?fps=15&targets=2&target_speed=0"
    async with flying_core(tmp_path, altitude=ALTITUDE_M, source=source, record=True, runs_dir=str(tmp_path),
                           processor="tests.recording.recorder_processors:RedCars") as core:
        cars = [target.position(0.0)[:2] for target in core.source.targets]
        home = core.controller.sim.home
        await asyncio.sleep(2.0)
        status = core.status()
        line = format_status(status, 0.0)
        await core.execute("f 1")  # malformed detections for a second
        await asyncio.sleep(1.0)
        broken = core.status()
        await core.execute("f 2")
        await asyncio.sleep(1.0)
        run_dir = core.recorder.run_dir
    run = dataset.load(run_dir)
    frames, detections = run.frames, run.detections

    # The status shows both, located, the most confident first; the --json line and the web page carry them.
    assert status.detections_total == 2 and [d.label for d in status.detections] == ["car", "car"]
    assert all(d.target.status == OK for d in status.detections)
    assert status.detections[0].score >= status.detections[1].score
    assert " | 2 detected, 2 tracks: #" in line and " car 0." in line and " m at " in line, line
    as_json = json.loads(json.dumps(status.as_dict(), default=str))
    assert as_json["detections_description"].startswith("2 detected, 2 tracks: #")
    assert as_json["tracks_total"] == 2 and {d["track_id"] for d in as_json["detections"]} == \
        {d.track_id for d in status.detections} and None not in {d.track_id for d in status.detections}
    assert {round(d["target"]["distance_m"]) for d in as_json["detections"]} == \
        {round(d.target.distance_m) for d in status.detections}
    assert broken.detections_total == 0 and "detections[0]: score nan must be in [0, 1]" in broken.processor_error

    # detections.csv: a row per detection, keyed by frame_id, on the frames' clock, each where a car is.
    assert list(detections.columns[1:]) == list(DETECTION_COLUMNS)  # after t_s
    assert set(detections["frame_id"]) <= set(frames["frame_id"])
    keyed = detections.merge(frames[["frame_id", "t_mono_ns"]], on="frame_id", suffixes=("", "_frame"))
    assert (keyed["t_mono_ns"] == keyed["t_mono_ns_frame"]).all()
    whole = (detections["box_x"] > 0) & (detections["box_y"] > 0) & (detections["box_x"] + detections["box_w"] < 640) \
        & (detections["box_y"] + detections["box_h"] < 480)
    located = detections[(detections["target_status"] == OK) & whole]
    assert len(located) >= 40 and located["frame_id"].value_counts().max() == 2, \
        detections["target_status"].value_counts()
    errors = []
    for lat, lon in located[["target_lat_deg", "target_lon_deg"]].to_numpy(dtype=np.float64):
        n, e, _ = home.to_local(lat, lon, 0.0)
        errors.append(min(math.hypot(n - car_n, e - car_e) for car_n, car_e in cars))
    assert np.percentile(errors, 95) <= 1.5, np.percentile(errors, [50, 95, 100])  # issue 39: <= 1 m at 20 m
    # Each car one track, the same before and after the second without detections (issue 50).
    nearest = [min(range(len(cars)), key=lambda i, n=n, e=e: math.hypot(n - cars[i][0], e - cars[i][1]))
               for n, e, _ in (home.to_local(lat, lon, 0.0) for lat, lon in
                               located[["target_lat_deg", "target_lon_deg"]].to_numpy(dtype=np.float64))]
    ids = located.assign(car=nearest).groupby("car")["track_id"].agg(["nunique", "first"])
    assert list(ids["nunique"]) == [1, 1] and ids["first"].nunique() == 2, ids
    assert (located["target_height_from"] == "rangefinder").all()
    assert np.allclose(detections.groupby("frame_id")["score"].sum(), 1.0, atol=1e-3)  # every one of a frame

    # The malformed frames: the processor's error, recorded, and none of their detections.
    failed = frames[frames["error"].fillna("").str.contains("detections[0]: score nan", regex=False)]
    assert len(failed) >= 5
    assert not set(failed["frame_id"]) & set(detections["frame_id"])
    assert failed["box_w"].notna().all()  # the box is read before the detections: it is kept
    assert set(detections.loc[detections["frame_id"] > failed["frame_id"].max(), "frame_id"])  # and they came back

    # Exported for QGIS and Google Earth: one point per located detection, with its label and score.
    assert runs_cli.main("export", [str(run_dir)]) == 0
    features = json.loads((run_dir / "track.geojson").read_text())["features"]
    points = [f for f in features if f["properties"]["kind"] == "detection"]
    ok = detections[detections["target_status"] == OK]
    assert [(p["properties"]["frame_id"], p["properties"]["label"]) for p in points] == \
        list(zip(ok["frame_id"], ok["label"], strict=True))
    assert np.allclose([p["geometry"]["coordinates"][:2] for p in points],
                       ok[["target_lon_deg", "target_lat_deg"]].to_numpy(dtype=np.float64), atol=1e-8)
    assert np.allclose([p["properties"]["score"] for p in points], ok["score"].to_numpy(dtype=np.float64))
    tracks = {f["properties"]["track_id"]: f for f in features if f["properties"]["kind"] == "track"}
    assert set(ids["first"]) <= set(tracks) and all(f["geometry"]["type"] == "LineString" for f in tracks.values())
    for track_id, feature in tracks.items():
        rows = ok[ok["track_id"] == track_id]
        assert np.allclose(feature["geometry"]["coordinates"],
                           rows[["target_lon_deg", "target_lat_deg"]].to_numpy(dtype=np.float64), atol=1e-8)
        assert feature["properties"]["label"] == "car" and len(feature["properties"]["times"]) == len(rows)
    kml = ET.parse(run_dir / "track.kml").getroot()
    names = [n.text for n in kml.iterfind(".//{http://www.opengis.net/kml/2.2}Placemark/"
                                          "{http://www.opengis.net/kml/2.2}name")]
    assert sum(name.startswith(("car 0.", "car 1.")) for name in names) == len(points)
    assert sorted(name for name in names if name.startswith("track ")) == sorted(f"track {i} car" for i in tracks)
