"""Telemetry that cannot be true, found at the boundary: a value outside what a vehicle can report is None, with a
reason, before any consumer (geo-location, landing targets, the ``sim:`` camera's pose, the recording) sees it.

The limits are physical, not a vehicle's envelope: latitude within +-90 degrees, longitude within +-180, an altitude
between the Dead Sea's shore and the stratosphere, heights above the ground not below it, angles within a turn,
speeds below an airliner's. A value beyond them is a broken sensor, a corrupted link or an edited recording.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from typing import Any

MAX_ALTITUDE_M = 20_000.0
"""No vehicle that carries this platform flies higher (above home or sea level); 10,000 km is a corrupted value."""

GROUND_MARGIN_M = 1.0
"""A height above the ground may read this much below zero (a sensor's noise on the ground); more is underground."""

LIMITS: dict[str, tuple[float, float]] = {
    "lat_deg": (-90.0, 90.0),
    "lon_deg": (-180.0, 180.0),
    "abs_alt_m": (-1_000.0, MAX_ALTITUDE_M),
    "rel_alt_m": (-MAX_ALTITUDE_M, MAX_ALTITUDE_M),
    "rangefinder_m": (-GROUND_MARGIN_M, MAX_ALTITUDE_M),
    "terrain_height_m": (-GROUND_MARGIN_M, MAX_ALTITUDE_M),
    "north_m": (-1e6, 1e6),
    "east_m": (-1e6, 1e6),
    "down_m": (-MAX_ALTITUDE_M, MAX_ALTITUDE_M),
    "roll_deg": (-180.0, 180.0),
    "pitch_deg": (-90.0, 90.0),
    "yaw_deg": (-360.0, 360.0),
    "gimbal_roll_deg": (-180.0, 180.0),
    "gimbal_pitch_deg": (-180.0, 180.0),
    "gimbal_yaw_deg": (-360.0, 360.0),
    "vn_ms": (-200.0, 200.0),
    "ve_ms": (-200.0, 200.0),
    "vd_ms": (-200.0, 200.0),
}
"""Telemetry field -> the (lowest, highest) value it can have (also :class:`~controllers.base.PoseSample` values)."""

POSE_FIELDS = {"position": ("north_m", "east_m", "down_m"), "attitude": ("roll_deg", "pitch_deg", "yaw_deg"),
               "gimbal": ("gimbal_roll_deg", "gimbal_pitch_deg", "gimbal_yaw_deg"),
               "gimbal_earth": ("gimbal_roll_deg", "gimbal_pitch_deg", "gimbal_yaw_deg")}
"""A pose sample's kind -> the telemetry fields its three values are."""


def implausible(name: str, value: Any) -> str:
    """Why telemetry field ``name`` cannot be ``value`` (``lat_deg 91 is outside [-90, 90]``), or ""."""
    limits = LIMITS.get(name)
    if limits is None or value is None or isinstance(value, bool):
        return ""
    try:
        number = float(value)
    except (TypeError, ValueError):
        return f"{name} {value!r:.40} is not a number"
    if not math.isfinite(number):
        return f"{name} {number} is not finite"
    low, high = limits
    if not low <= number <= high:
        return f"{name} {number:g} is outside [{low:g}, {high:g}]"
    return ""


def problems(update: Mapping[str, Any]) -> Iterator[tuple[str, str]]:
    """(field, why) for each value of ``update`` that cannot be true."""
    for name, value in update.items():
        if why := implausible(name, value):
            yield name, why


def pose_problem(kind: str, values: tuple[float, float, float]) -> str:
    """Why a pose sample of ``kind`` cannot have ``values``, or ""."""
    names = POSE_FIELDS.get(kind, ())
    return next((why for name, value in zip(names, values, strict=False) if (why := implausible(name, value))), "")
