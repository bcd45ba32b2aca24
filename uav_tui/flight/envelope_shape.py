"""The horizontal shapes of the autonomy envelope: a circle around home and a polygon read from a GeoJSON file.

Both work in local metres (north, east) from home, the frame the autopilot reports its position in. Each answers
three questions for :mod:`uav_tui.flight.envelope`: how far inside a point is (negative outside) and which way is
out there, and where a straight move first leaves it. Plain scalar math: a 100-vertex polygon costs tens of
microseconds a vector (``scripts/bench_envelope.py``), which a general geometry library's object per call would not.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, Protocol

from uav_tui.flight.geolocate import EARTH_RADIUS_M

Point = tuple[float, float]
"""(north, east) metres from home."""

MAX_VERTICES = 10_000
"""A fence polygon with more vertices than this is not a field's boundary (and would slow every vector)."""


class Shape(Protocol):
    def nearest(self, p: Point) -> tuple[float, Point]:
        """``(depth, outward)``: metres inside the boundary (negative outside) and the unit vector pointing out
        of the shape at the nearest boundary point."""
        ...

    def exit_fraction(self, p: Point, d: Point) -> float | None:
        """The first ``s`` in [0, 1] at which ``p + s*d`` (``p`` inside) is on the boundary; None if it stays in."""
        ...

    def describe(self) -> str: ...


class Circle:
    """Within ``radius_m`` of home."""

    def __init__(self, radius_m: float) -> None:
        self.radius_m = radius_m

    def describe(self) -> str:
        return f"the {self.radius_m:g} m radius"

    def nearest(self, p: Point) -> tuple[float, Point]:
        r = math.hypot(*p)
        return self.radius_m - r, ((p[0] / r, p[1] / r) if r > 1e-9 else (1.0, 0.0))

    def exit_fraction(self, p: Point, d: Point) -> float | None:
        a = d[0] * d[0] + d[1] * d[1]
        if a < 1e-18:
            return None
        b = 2 * (p[0] * d[0] + p[1] * d[1])
        c = p[0] * p[0] + p[1] * p[1] - self.radius_m ** 2
        s = (-b + math.sqrt(max(0.0, b * b - 4 * a * c))) / (2 * a)
        return max(0.0, s) if s <= 1.0 else None


class Polygon:
    """Inside a simple polygon (no self-intersection), given by its vertices in local metres."""

    def __init__(self, vertices: list[Point], name: str = "the polygon") -> None:
        self.vertices = vertices
        self.name = name
        pairs = [(vertices[i - 1], vertices[i]) for i in range(len(vertices)) if vertices[i - 1] != vertices[i]]
        sign = 1.0 if sum(a[0] * b[1] - b[0] * a[1] for a, b in pairs) > 0 else -1.0  # the turning sense
        self._edges = [(a, b, (b[0] - a[0], b[1] - a[1]), (b[0] - a[0]) ** 2 + (b[1] - a[1]) ** 2,
                        _unit((b[1] - a[1]) * sign, (a[0] - b[0]) * sign)) for a, b in pairs]
        """Per edge: its ends, direction, squared length and outward unit normal, computed once."""

    def describe(self) -> str:
        return self.name

    def contains(self, p: Point) -> bool:
        """Even-odd ray casting along +east."""
        inside = False
        n, e = p
        for (n1, e1), (n2, _), (dn, de), _, _ in self._edges:
            if (n1 > n) != (n2 > n) and e < e1 + (n - n1) * de / dn:
                inside = not inside
        return inside

    def nearest(self, p: Point) -> tuple[float, Point]:
        best, outward = math.inf, (1.0, 0.0)
        n, e = p
        for (n1, e1), _, (dn, de), length2, normal in self._edges:
            u = ((n - n1) * dn + (e - e1) * de) / length2
            u = 0.0 if u < 0.0 else 1.0 if u > 1.0 else u
            qn, qe = n1 + u * dn - n, e1 + u * de - e
            distance2 = qn * qn + qe * qe
            if distance2 < best:
                best, outward = distance2, normal
        return (math.sqrt(best) if self.contains(p) else -math.sqrt(best)), outward

    def exit_fraction(self, p: Point, d: Point) -> float | None:
        first: float | None = None
        pn, pe = p
        dn, de = d
        for (an, ae), _, (en, ee), _, _ in self._edges:
            denominator = dn * ee - de * en
            if abs(denominator) < 1e-12:
                continue
            wn, we = an - pn, ae - pe
            s = (wn * ee - we * en) / denominator
            if 0.0 <= s <= 1.0 and (first is None or s < first):
                u = (wn * de - we * dn) / denominator
                if 0.0 <= u <= 1.0:
                    first = s
        return first


def _unit(n: float, e: float) -> Point:
    length = math.hypot(n, e)
    return n / length, e / length


def _crossing(p: Point, d: Point, a: Point, b: Point) -> float | None:
    """Where on ``p + s*d`` (s in [0, 1]) the segment a-b is crossed, or None (parallel: never)."""
    en, ee = b[0] - a[0], b[1] - a[1]
    denominator = d[0] * ee - d[1] * en
    if abs(denominator) < 1e-12:
        return None
    wn, we = a[0] - p[0], a[1] - p[1]
    s = (wn * ee - we * en) / denominator
    u = (wn * d[1] - we * d[0]) / denominator
    return s if 0.0 <= s <= 1.0 and 0.0 <= u <= 1.0 else None


def read_polygon(path: str) -> list[tuple[float, float]]:
    """The (lat, lon) vertices of the one polygon in a GeoJSON file; ValueError saying what is wrong with it.

    Takes a Polygon geometry, a Feature holding one, or a FeatureCollection with exactly one polygon feature;
    the outer ring only (a hole is refused: the envelope is one region). Refused too: fewer than three distinct
    vertices, coordinates that are not longitude/latitude, and a ring that crosses itself.
    """
    try:
        data = json.loads(Path(path).expanduser().read_text(encoding="utf-8"))
    except OSError as exc:
        raise ValueError(f"cannot read the polygon file {path}: {exc.strerror or exc}") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"the polygon file {path} is not GeoJSON ({exc}); export the field boundary as a "
                         "GeoJSON Polygon") from None
    rings = _rings(data, path)
    if len(rings) != 1:
        raise ValueError(f"the polygon in {path} has {len(rings) - 1} hole(s): the envelope is one area without "
                         "holes; remove them")
    vertices = _vertices(rings[0], path)
    if (crossed := _self_crossing(vertices)) is not None:
        raise ValueError(f"the polygon in {path} crosses itself (edges {crossed[0] + 1} and {crossed[1] + 1}); "
                         "fix the boundary so that no two edges cross")
    return vertices


def _rings(data: Any, path: str) -> list[Any]:
    if isinstance(data, dict) and data.get("type") == "FeatureCollection":
        polygons = [f.get("geometry") for f in data.get("features") or [] if isinstance(f, dict)
                    and isinstance(f.get("geometry"), dict) and f["geometry"].get("type") == "Polygon"]
        if len(polygons) != 1:
            raise ValueError(f"the polygon file {path} holds {len(polygons)} Polygon features; it needs exactly one")
        data = polygons[0]
    elif isinstance(data, dict) and data.get("type") == "Feature":
        data = data.get("geometry")
    if not isinstance(data, dict) or data.get("type") != "Polygon" or not isinstance(data.get("coordinates"), list) \
            or not data["coordinates"]:
        raise ValueError(f"the polygon file {path} holds no GeoJSON Polygon (a MultiPolygon, a line or a point "
                         "cannot bound a flight)")
    return list(data["coordinates"])


def _vertices(ring: Any, path: str) -> list[tuple[float, float]]:
    vertices: list[tuple[float, float]] = []
    for position in ring if isinstance(ring, list) else []:
        if not (isinstance(position, list) and len(position) >= 2 and all(
                isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x) for x in position[:2])):
            raise ValueError(f"the polygon in {path} has a position that is not [longitude, latitude]: "
                             f"{str(position)[:60]}")
        lon, lat = float(position[0]), float(position[1])
        if not (-180 <= lon <= 180 and -90 <= lat <= 90):
            raise ValueError(f"the polygon in {path} has a position off the earth: [{lon:g}, {lat:g}] "
                             "(GeoJSON is [longitude, latitude])")
        if not vertices or vertices[-1] != (lat, lon):
            vertices.append((lat, lon))
    if len(vertices) > 1 and vertices[0] == vertices[-1]:
        vertices.pop()  # GeoJSON closes the ring by repeating the first position
    if len(vertices) < 3:
        raise ValueError(f"the polygon in {path} has {len(vertices)} distinct vertices; it needs at least three")
    if len(vertices) > MAX_VERTICES:
        raise ValueError(f"the polygon in {path} has {len(vertices)} vertices, more than {MAX_VERTICES}; simplify it")
    return vertices


def _self_crossing(vertices: list[tuple[float, float]]) -> tuple[int, int] | None:
    """Two edges (indices) that cross or touch and are not neighbours, or None."""
    edges = [(vertices[i], vertices[(i + 1) % len(vertices)]) for i in range(len(vertices))]
    for i, (a, b) in enumerate(edges):
        for j in range(i + 2, len(edges)):
            if i == 0 and j == len(edges) - 1:
                continue  # neighbours through the closing vertex
            c, d = edges[j]
            if _crossing(a, (b[0] - a[0], b[1] - a[1]), c, d) is not None:
                return i, j
    return None


def to_local(vertices: list[tuple[float, float]], origin: tuple[float, float]) -> list[Point]:
    """(lat, lon) degrees -> (north, east) metres from ``origin`` (flat earth, as geo-location converts)."""
    lat0, lon0 = origin
    east_scale = EARTH_RADIUS_M * math.cos(math.radians(lat0))
    return [(math.radians(lat - lat0) * EARTH_RADIUS_M, math.radians(lon - lon0) * east_scale)
            for lat, lon in vertices]


def origin_of(lat_deg: float, lon_deg: float, north_m: float, east_m: float) -> tuple[float, float]:
    """The (lat, lon) of the local origin (home) from a position given both ways."""
    lat0 = lat_deg - math.degrees(north_m / EARTH_RADIUS_M)
    return lat0, lon_deg - math.degrees(east_m / (EARTH_RADIUS_M * math.cos(math.radians(lat0))))
