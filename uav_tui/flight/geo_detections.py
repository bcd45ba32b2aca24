"""The processor's ``detections`` as the interfaces show them: the most confident few, each geo-located like ``box``."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from uav_tui.flight.geolocate import GeoFix, locate_row, range_and_bearing
from uav_tui.output.text import safe
from uav_values.detections import Detected

if TYPE_CHECKING:
    from uav_values.camera import CameraModel

MAX_SHOWN = 5
"""Detections shown on the status (TUI, headless line, web page): the most confident; the rest are counted."""


@dataclass(frozen=True, slots=True)
class LocatedDetection(Detected):
    """One detection as shown: its label made safe to show, and its ground position."""

    target: GeoFix


def locate_shown(detections: tuple[Detected, ...], camera: CameraModel | None, telemetry: Mapping[str, Any],
                 at_ns: int | None) -> tuple[LocatedDetection, ...]:
    """The :data:`MAX_SHOWN` most confident of ``detections``, located with ``telemetry`` (at the capture ``at_ns``)."""
    best = sorted(detections, key=lambda found: -found.score)[:MAX_SHOWN]
    return tuple(LocatedDetection(found.box, safe(found.label), found.score,
                                  locate_row(camera, found.box, telemetry, at_ns=at_ns), track_id=found.track_id)
                 for found in best)


def count_tracks(detections: tuple[Detected, ...]) -> int:
    """How many tracks ``detections`` are of (the distinct ``track_id``; a detection without one is none)."""
    return len({found.track_id for found in detections if found.track_id is not None})


def describe_shown(shown: tuple[LocatedDetection, ...], total: int, tracks: int = 0) -> str:
    """``3 detected, 2 tracks: #4 person 0.91 12 m at 045 deg, car 0.80 no position, +1 more`` (``#`` the track
    id); "" when none was."""
    if not total:
        return ""
    parts = [f"{'' if found.track_id is None else f'#{found.track_id} '}{found.label} {found.score:.2f} "
             f"{range_and_bearing(found.target) or 'no position'}" for found in shown]
    if total > len(shown):
        parts.append(f"+{total - len(shown)} more")
    return f"{total} detected{f', {tracks} tracks' if tracks else ''}: {', '.join(parts)}"

