"""The autopilot's height above the terrain, as a ``terrain_height_m`` telemetry update.

PX4 reports it in ALTITUDE (MAVSDK's ``altitude`` stream) as ``bottom_clearance``, its estimate of the distance to
the ground (``dist_bottom``, NaN when it has none). Not ``altitude_terrain``: MAVLink calls it the altitude above the
terrain, but PX4 (v1.16, ALTITUDE.hpp) sends the terrain's own altitude in its local frame there (its SIH flying at
20 m: 0.3-1.0 m). ArduPilot does not send ALTITUDE; with ``TERRAIN_ENABLE`` it streams TERRAIN_REPORT
(``current_height``: the vehicle's height above the terrain under it; ``spacing`` 0 when it has no terrain data
there), which MAVSDK's telemetry does not expose: it is read as a raw message.
"""

from __future__ import annotations

import contextlib
import json
import math
from collections.abc import AsyncGenerator
from typing import Any

from mavsdk.asyncio.plugins.mavlink_direct import MavlinkDirectAsync, MavlinkMessage

Update = dict[str, Any]

def _height(value: Any) -> float | None:
    """``value`` as a height when it is a finite number, not negative (MAVLink's "unknown")."""
    try:
        height = float(value)
    except (TypeError, ValueError):
        return None
    return height if math.isfinite(height) and height >= 0 else None


def from_altitude(a: Any) -> Update:
    """MAVSDK's Altitude (ALTITUDE): ``bottom_clearance``, or None when it reports none."""
    return {"terrain_height_m": _height(a.bottom_clearance_m)}


def from_terrain_report(message: MavlinkMessage) -> Update:
    """A TERRAIN_REPORT (raw, MavlinkDirect): ``current_height``, None without terrain data (``spacing`` 0)."""
    try:
        fields = json.loads(message.fields_json)
        known = int(fields["spacing"]) > 0
    except (ValueError, KeyError, TypeError):
        return {}
    return {"terrain_height_m": _height(fields.get("current_height")) if known else None}


async def terrain_reports(direct: MavlinkDirectAsync, system_id: int) -> AsyncGenerator[Update, None]:
    """The updates of the autopilot's (``system_id``'s) TERRAIN_REPORTs, as they arrive."""
    async with contextlib.aclosing(direct.subscribe_message("TERRAIN_REPORT")) as messages:  # unsubscribed when closed
        async for message in messages:
            if message.system_id == system_id and (update := from_terrain_report(message)):
                yield update
