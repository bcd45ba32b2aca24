"""``uav-tui export`` of an edited recording (issue 47): impossible coordinates (latitude 91, longitude 200, an
infinite altitude) never reach GeoJSON or KML, and the GeoJSON is strict JSON (no ``Infinity``)."""

from __future__ import annotations

import csv
import io
import json
import re
import time
from pathlib import Path

import numpy as np

from tests.recording.recorder_fakes import FakeCore
from uav_tui.config import RecordingConfig
from uav_tui.recorded.runs_cli import main as tools_main
from uav_tui.recording import Recorder

SAMPLES = 20


def _flown_run(runs_dir: Path) -> Path:
    core = FakeCore()
    recorder = Recorder.open(RecordingConfig(runs_dir=str(runs_dir)), {"processor": {"name": "track"}},
                             telemetry_expected=True)
    core.attach(recorder)
    image = np.zeros((48, 64, 3), np.uint8)
    for i in range(SAMPLES):
        core.telemetry.apply({"lat_deg": 47.0 + 1e-5 * i, "lon_deg": 8.0, "abs_alt_m": 500.0, "rel_alt_m": 10.0})
        time.sleep(0.004)
        core.process(image, i + 1, lambda result: None)
    recorder.close()
    return recorder.run_dir


def _edit_telemetry(run_dir: Path, edits: dict[int, tuple[str, str]]) -> None:
    path = run_dir / "telemetry.csv"
    rows = list(csv.reader(path.read_text().splitlines()))
    located = [i for i, row in enumerate(rows) if i and row[rows[0].index("lat_deg")]]
    for nth, (column, value) in edits.items():
        rows[located[nth]][rows[0].index(column)] = value
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerows(rows)
    path.write_text(out.getvalue())


def _refuse_constant(name: str) -> float:
    raise AssertionError(f"track.geojson holds {name}, which is not JSON")


def test_impossible_coordinates_are_left_out_of_geojson_and_kml(tmp_path: Path) -> None:
    run_dir = _flown_run(tmp_path / "runs")
    _edit_telemetry(run_dir, {2: ("lat_deg", "91"), 4: ("lon_deg", "200"), 6: ("abs_alt_m", "inf"),
                              8: ("abs_alt_m", "1e10")})
    assert tools_main("export", [str(run_dir)]) == 0
    geojson = json.loads((run_dir / "track.geojson").read_text(), parse_constant=_refuse_constant)
    track = [f for f in geojson["features"] if f["properties"]["kind"] == "vehicle"][0]["geometry"]["coordinates"]
    assert len(track) >= SAMPLES - 4 - 2 and all(-180 <= lon <= 180 and -90 <= lat <= 90 and alt < 20_000
                                                for lon, lat, alt in track)
    kml = (run_dir / "track.kml").read_text()
    points = [tuple(map(float, p.split(","))) for p in re.search(r"<coordinates>(.*?)</coordinates>", kml,
                                                                   re.S).group(1).split()]
    assert len(points) == len(track) and all(abs(lat) <= 90 and abs(lon) <= 180 and alt < 20_000
                                             for lon, lat, alt in points)
