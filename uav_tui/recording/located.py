"""The geo-location cells of a recorded frame: its ``box``'s (frames.csv) and each of its ``detections``
(detections.csv, one row per detection, keyed by ``frame_id``)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from uav_tui.flight.geolocate import GeoFix, locate_row
from uav_values.detections import Detected

if TYPE_CHECKING:
    from uav_values.camera import CameraModel

GEO_COLUMNS: tuple[str, ...] = ("target_lat_deg", "target_lon_deg", "target_alt_m", "target_uncertainty_m",
                                 "target_status", "target_height_from", "target_height_note")
"""Where a box's centre is on the ground (:mod:`uav_tui.flight.geolocate`, from the camera model and the telemetry
at the capture): latitude, longitude, ground altitude AMSL, 1-sigma uncertainty in metres, the status (``ok``; empty
without a box; else why there is no position), where the height above the ground came from
(:data:`uav_tui.flight.geolocate.HEIGHT_SIGMAS`: ``rangefinder``, ``terrain`` or ``home``) and why a better one was
not used (``rangefinder 0.8 s old``: older than :data:`uav_tui.flight.geolocate.READING_MAX_AGE_S`)."""

DETECTION_COLUMNS: tuple[str, ...] = ("frame_id", "t_wall_ns", "t_mono_ns", "index", "track_id", "label", "score",
                                      "box_x", "box_y", "box_w", "box_h", *GEO_COLUMNS)
"""detections.csv: one row per detection the processor reported (its ``detections`` attribute), keyed by the
frame's ``frame_id`` and capture times (the frames.csv row's), ``index`` its place in the processor's list,
``track_id`` the object it is (:mod:`uav_tui.hosting.tracks`; empty while it is no track yet); its box
geo-located as frames.csv's ``box`` is, with the same telemetry. A frame with no detections has no row."""


def geo_cells(fix: GeoFix) -> tuple[Any, ...]:
    """The :data:`GEO_COLUMNS` of a fix (coordinates to 1e-8 degrees, ~1 mm)."""
    if fix.lat_deg is None or fix.lon_deg is None or fix.uncertainty_m is None:
        return None, None, None, None, fix.status, None, None
    alt = None if fix.alt_m is None else round(fix.alt_m, 3)
    return (round(fix.lat_deg, 8), round(fix.lon_deg, 8), alt, round(fix.uncertainty_m, 3), fix.status, fix.height_from,
            fix.height_note or None)


def detection_rows(frame_id: int, t_wall_ns: int, t_mono_ns: int, detections: tuple[Detected, ...],
                   camera: CameraModel | None, telemetry: Mapping[str, Any]) -> list[list[Any]]:
    """The :data:`DETECTION_COLUMNS` of each detection of one frame, located with ``telemetry`` (at its capture)."""
    return [[frame_id, t_wall_ns, t_mono_ns, index, found.track_id, found.label, round(found.score, 4), *found.box,
             *geo_cells(locate_row(camera, found.box, telemetry, at_ns=t_mono_ns))]
            for index, found in enumerate(detections)]
