"""The autopilot's height above the terrain, as a ``terrain_height_m`` telemetry update.

PX4 reports it in ALTITUDE (MAVSDK's ``altitude`` stream): ``altitude_terrain`` ("altitude above terrain", from a
terrain estimate or an altimeter; below -1000 means unknown), else ``bottom_clearance`` (the clear space below,
negative when unmeasured). ArduPilot does not send ALTITUDE; with ``TERRAIN_ENABLE`` it streams TERRAIN_REPORT
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

UNKNOWN_TERRAIN_M = -1000.0
"""ALTITUDE's ``altitude_terrain`` at or below this is unknown (MAVLink's definition)."""


def _height(value: Any, low: float) -> float | None:
    """``value`` as a height when it is a finite number above ``low``."""
    try:
        height = float(value)
    except (TypeError, ValueError):
        return None
    return height if math.isfinite(height) and height > low else None


def from_altitude(a: Any) -> Update:
    """MAVSDK's Altitude (ALTITUDE): the height above the terrain, or None when it reports none."""
    height = _height(a.altitude_terrain_m, UNKNOWN_TERRAIN_M)
    if height is None:
        height = _height(a.bottom_clearance_m, -1e-9)
    return {"terrain_height_m": height}


def from_terrain_report(message: MavlinkMessage) -> Update:
    """A TERRAIN_REPORT (raw, MavlinkDirect): ``current_height``, None without terrain data (``spacing`` 0)."""
    try:
        fields = json.loads(message.fields_json)
        known = int(fields["spacing"]) > 0
    except (ValueError, KeyError, TypeError):
        return {}
    return {"terrain_height_m": _height(fields.get("current_height"), -math.inf) if known else None}


async def terrain_reports(direct: MavlinkDirectAsync, system_id: int) -> AsyncGenerator[Update, None]:
    """The updates of the autopilot's (``system_id``'s) TERRAIN_REPORTs, as they arrive."""
    async with contextlib.aclosing(direct.subscribe_message("TERRAIN_REPORT")) as messages:  # unsubscribed when closed
        async for message in messages:
            if message.system_id == system_id and (update := from_terrain_report(message)):
                yield update
