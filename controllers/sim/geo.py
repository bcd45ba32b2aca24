"""Flat-earth conversion between the local NED frame (origin at home) and WGS84 latitude/longitude."""

from __future__ import annotations

import math
from dataclasses import dataclass

EARTH_RADIUS_M = 6_371_000.0
"""Mean earth radius used by the flat-earth approximation."""


@dataclass(frozen=True, slots=True)
class Home:
    """The local origin: where the vehicle boots, and where RTL returns to.

    ``alt_m`` is AMSL at ground level; down = 0 is the ground.
    """

    lat_deg: float = 47.397742
    lon_deg: float = 8.545594
    alt_m: float = 488.0

    @classmethod
    def parse(cls, text: str) -> Home:
        """Parse ``"LAT,LON,ALT"`` (degrees, degrees, metres AMSL).

        Raises:
            ValueError: the text is not three comma-separated numbers in range.
        """
        parts = [p.strip() for p in text.split(",")]
        if len(parts) != 3:
            raise ValueError(f"home must be LAT,LON,ALT, got {text!r}")
        lat, lon, alt = (float(p) for p in parts)
        if not (-90.0 < lat < 90.0 and -180.0 <= lon <= 180.0 and math.isfinite(alt)):
            raise ValueError(f"home out of range: {text!r}")
        return cls(lat, lon, alt)

    def to_global(self, north: float, east: float, down: float) -> tuple[float, float, float]:
        """NED metres from home -> (lat deg, lon deg, alt m AMSL)."""
        lat = self.lat_deg + math.degrees(north / EARTH_RADIUS_M)
        lon = self.lon_deg + math.degrees(east / (EARTH_RADIUS_M * math.cos(math.radians(self.lat_deg))))
        return lat, lon, self.alt_m - down

    def to_local(self, lat: float, lon: float, alt: float) -> tuple[float, float, float]:
        """(lat deg, lon deg, alt m AMSL) -> NED metres from home."""
        north = math.radians(lat - self.lat_deg) * EARTH_RADIUS_M
        east = math.radians(lon - self.lon_deg) * EARTH_RADIUS_M * math.cos(math.radians(self.lat_deg))
        return north, east, self.alt_m - alt


def parse_wind(text: str) -> tuple[float, float]:
    """``"N,E"`` in m/s -> (north, east); ValueError when it is not two finite numbers."""
    parts = text.split(",")
    if len(parts) != 2:
        raise ValueError(f"wind must be N,E (m/s), got {text!r}")
    north, east = (float(part) for part in parts)
    if not (math.isfinite(north) and math.isfinite(east)):
        raise ValueError(f"wind must be finite, got {text!r}")
    return north, east
