"""A run's vehicle track and target positions as GeoJSON (QGIS) or KML (Google Earth): ``uav-tui export RUN``.

The track is the telemetry's positions (latitude, longitude, altitude AMSL), the targets are the frames whose box
was geo-located (``target_status`` ``ok``), each with its time (UTC), frame id and 1-sigma uncertainty; the
detections are the geo-located rows of detections.csv, likewise, with their label and score; each track (the
detections of one ``track_id``, :mod:`uav_tui.hosting.tracks`) is one line through its located detections.
Coordinates that cannot be true (latitude 91, an infinite altitude: an edited or corrupted recording) are left
out, never written: no map takes them, and JSON has no ``Infinity``.
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pandas as pd

from uav_tui.flight.geolocate import OK
from uav_tui.flight.telemetry_sanity import LIMITS
from uav_tui.recorded.dataset import Dataset
from uav_tui.recording.run_info import replace_file

KML_NS = "http://www.opengis.net/kml/2.2"


def _possible(values: pd.Series, field: str) -> pd.Series:
    """Which of ``values`` (numbers or text) telemetry field ``field`` can be (NaN and infinities cannot)."""
    return pd.to_numeric(values, errors="coerce").between(*LIMITS[field])


def _track(run: Dataset) -> pd.DataFrame:
    table = run.telemetry[["lat_deg", "lon_deg", "abs_alt_m"]].apply(pd.to_numeric, errors="coerce")
    table = table[_possible(table["lat_deg"], "lat_deg") & _possible(table["lon_deg"], "lon_deg")
                  & _possible(table["abs_alt_m"], "abs_alt_m")]
    return table[(table["lat_deg"] != 0) | (table["lon_deg"] != 0)]  # 0,0: an autopilot without a fix yet


def _located(table: pd.DataFrame, *numbers: str) -> pd.DataFrame:
    """The rows of ``table`` (frames or detections) whose box was geo-located at a possible place, that name their
    frame and have finite ``numbers`` (written as JSON numbers); an impossible target altitude is left out (NaN)."""
    located = table[(table["target_status"] == OK).fillna(False)]
    located = located.dropna(subset=["target_lat_deg", "target_lon_deg", "frame_id"])
    keep = _possible(located["target_lat_deg"], "lat_deg") & _possible(located["target_lon_deg"], "lon_deg")
    for name in ("target_uncertainty_m", *numbers):
        keep &= pd.to_numeric(located[name], errors="coerce").abs().lt(math.inf)
    located = located[keep]
    return located.assign(target_alt_m=located["target_alt_m"].where(_possible(located["target_alt_m"], "abs_alt_m")))


def without_frame_id(run: Dataset) -> int:
    """Geo-located rows left out of the export because their ``frame_id`` is empty (a damaged file: the cell did
    not read as a whole number, which ``run.problems`` names)."""
    return sum(int(((table["target_status"] == OK).fillna(False) & table["frame_id"].isna()).sum())
               for table in (run.frames, run.detections))


def _points(run: Dataset) -> list[tuple[pd.Timestamp, pd.Series, str]]:
    """Every located target, then every located detection: (time, row, name)."""
    return [*((time, row, "target") for time, row in _located(run.frames).iterrows()),
            *((time, row, f"{row['label']} {float(row['score']):.2f}")
              for time, row in _located(run.detections, "score").iterrows())]


def _tracks(run: Dataset) -> list[tuple[int, str, pd.DataFrame]]:
    """Each track with at least two located detections: (track_id, its most frequent label, its rows in time
    order)."""
    located = _located(run.detections, "score").dropna(subset=["track_id"])
    return [(int(track_id), str(rows["label"].mode().iloc[0]), rows.sort_values("t_mono_ns"))
            for track_id, rows in located.groupby("track_id") if len(rows) >= 2]


def _when(time: pd.Timestamp) -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%S.%fZ")


def geojson(run: Dataset) -> dict[str, Any]:
    """A FeatureCollection: the vehicle's track (LineString with ``times``), then one Point per located target."""
    track = _track(run)
    features: list[dict[str, Any]] = []
    if len(track) >= 2:
        features.append({"type": "Feature", "properties": {"kind": "vehicle", "times": [_when(t) for t in track.index]},
                         "geometry": {"type": "LineString", "coordinates": [
                             [round(lon, 8), round(lat, 8), round(alt, 3)] for lat, lon, alt in track.to_numpy()]}})
    for time, row, name in _points(run):
        point = [round(float(row["target_lon_deg"]), 8), round(float(row["target_lat_deg"]), 8)]
        if pd.notna(row["target_alt_m"]):
            point.append(round(float(row["target_alt_m"]), 3))
        properties = {"kind": "target", "time": _when(time), "frame_id": int(row["frame_id"]),
                      "uncertainty_m": float(row["target_uncertainty_m"])}
        if name != "target":
            properties |= {"kind": "detection", "label": str(row["label"]), "score": float(row["score"])}
        features.append({"type": "Feature", "geometry": {"type": "Point", "coordinates": point},
                         "properties": properties})
    for track_id, label, rows in _tracks(run):
        features.append({"type": "Feature", "properties": {
            "kind": "track", "track_id": track_id, "label": label, "times": [_when(t) for t in rows.index]},
            "geometry": {"type": "LineString", "coordinates": [
                [round(lon, 8), round(lat, 8)] for lon, lat in rows[["target_lon_deg", "target_lat_deg"]].to_numpy()]}})
    return {"type": "FeatureCollection", "features": features}


def kml(run: Dataset) -> str:
    """A KML 2.2 document: the vehicle's track (LineString, absolute altitude), one timed Placemark per target and
    per detection, one LineString per detections' track (on the ground)."""
    ET.register_namespace("", KML_NS)
    root = ET.Element(f"{{{KML_NS}}}kml")
    document = ET.SubElement(root, f"{{{KML_NS}}}Document")
    ET.SubElement(document, f"{{{KML_NS}}}name").text = run.path.name
    track = _track(run)
    if len(track) >= 2:
        placemark = ET.SubElement(document, f"{{{KML_NS}}}Placemark")
        ET.SubElement(placemark, f"{{{KML_NS}}}name").text = "vehicle"
        line = ET.SubElement(placemark, f"{{{KML_NS}}}LineString")
        ET.SubElement(line, f"{{{KML_NS}}}altitudeMode").text = "absolute"
        ET.SubElement(line, f"{{{KML_NS}}}coordinates").text = " ".join(
            f"{lon:.8f},{lat:.8f},{alt:.3f}" for lat, lon, alt in track.to_numpy())
    for time, row, name in _points(run):
        placemark = ET.SubElement(document, f"{{{KML_NS}}}Placemark")
        ET.SubElement(placemark, f"{{{KML_NS}}}name").text = f"{name}, frame {int(row['frame_id'])}"
        ET.SubElement(placemark, f"{{{KML_NS}}}description").text = \
            f"+-{float(row['target_uncertainty_m']):.1f} m (1 sigma)"
        ET.SubElement(ET.SubElement(placemark, f"{{{KML_NS}}}TimeStamp"), f"{{{KML_NS}}}when").text = _when(time)
        point = ET.SubElement(placemark, f"{{{KML_NS}}}Point")
        ET.SubElement(point, f"{{{KML_NS}}}altitudeMode").text = "clampToGround"
        ET.SubElement(point, f"{{{KML_NS}}}coordinates").text = \
            f"{float(row['target_lon_deg']):.8f},{float(row['target_lat_deg']):.8f}"
    for track_id, label, rows in _tracks(run):
        placemark = ET.SubElement(document, f"{{{KML_NS}}}Placemark")
        ET.SubElement(placemark, f"{{{KML_NS}}}name").text = f"track {track_id} {label}"
        span = ET.SubElement(placemark, f"{{{KML_NS}}}TimeSpan")
        ET.SubElement(span, f"{{{KML_NS}}}begin").text = _when(rows.index[0])
        ET.SubElement(span, f"{{{KML_NS}}}end").text = _when(rows.index[-1])
        line = ET.SubElement(placemark, f"{{{KML_NS}}}LineString")
        ET.SubElement(line, f"{{{KML_NS}}}altitudeMode").text = "clampToGround"
        ET.SubElement(line, f"{{{KML_NS}}}coordinates").text = " ".join(
            f"{lon:.8f},{lat:.8f}" for lon, lat in rows[["target_lon_deg", "target_lat_deg"]].to_numpy())
    ET.indent(root)
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"


def write(run: Dataset, formats: list[str]) -> list[Path]:
    """Write ``track.geojson`` / ``track.kml`` into the run's folder (each whole or not at all); returns the paths
    written.

    Raises:
        OSError: a file could not be written (a full disk).
    """
    written = []
    for name in formats:
        path = run.path / f"track.{name}"
        text = json.dumps(geojson(run), allow_nan=False) if name == "geojson" else kml(run)
        replace_file(path, text.encode())
        written.append(path)
    return written
