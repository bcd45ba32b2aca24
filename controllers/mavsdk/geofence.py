"""The autopilot's geofence plan as MAVSDK downloads it (PX4's mission-type fence): how many areas it holds."""

from __future__ import annotations

from mavsdk.asyncio import System
from mavsdk.asyncio.plugins.geofence import FenceType, GeofenceAsync

from controllers.fence import FencePlan


async def download_plan(system: System) -> FencePlan:
    """The plan's inclusion and exclusion areas (polygons and circles alike), counted."""
    data = await GeofenceAsync(system).download_geofence()
    kinds = [area.fence_type for area in (*data.polygons, *data.circles)]
    return FencePlan(kinds.count(FenceType.INCLUSION), kinds.count(FenceType.EXCLUSION))
