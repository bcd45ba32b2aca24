"""The autopilot's own fence, read at connect: said on every interface, and required when configured."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from mavsdk.asyncio.plugins.geofence import GeofenceAsync
from mavsdk.plugins.geofence import Circle, FenceType, GeofenceData, Point, Polygon

from controllers.autopilots import Autopilot
from controllers.errors import ControllerError
from controllers.failsafe import ParamAccess
from controllers.fence import FencePlan, read_fence
from tests.core.flight_helpers import steering_config
from uav_tui.core import UavCore
from uav_tui.errors import UavError


class _Params:
    """An autopilot's parameters as MAVSDK's Param plugin returns them (no SITL here)."""

    def __init__(self, **values: float) -> None:
        self.values = values

    async def get_param_int(self, name: str) -> int:
        if name not in self.values:
            raise ControllerError(f"{name}: no such parameter")
        return int(self.values[name])

    async def get_param_float(self, name: str) -> float:
        return float(self.values[name])


async def _bound(name: str, call: Any) -> Any:
    return await call()


@pytest.mark.parametrize(("values", "enabled", "summary"), [
    ({"FENCE_ENABLE": 0}, False, "autopilot fence: none (FENCE_ENABLE is 0)"),
    ({"FENCE_ENABLE": 1, "FENCE_ACTION": 0}, False, "autopilot fence: reports only (FENCE_ACTION is 0)"),
    ({"FENCE_ENABLE": 1, "FENCE_ACTION": 1, "FENCE_TYPE": 3, "FENCE_RADIUS": 80.0, "FENCE_ALT_MAX": 60.0}, True,
     "autopilot fence: circle 80 m, ceiling 60 m (ArduPilot FENCE_*)"),
    ({}, False, "autopilot fence: unknown, a parameter could not be read (FENCE_ENABLE: no such parameter)"),
])
async def test_ardupilot_fence_parameters_say_whether_a_fence_acts(values: dict[str, float], enabled: bool,
                                                                   summary: str) -> None:
    report = await read_fence(Autopilot.ARDUPILOT, ParamAccess(_Params(**values), _bound))
    assert (report.enabled, report.summary) == (enabled, summary)


async def test_without_a_fence_the_platform_says_so_and_autonomy_is_refused_when_one_is_required(
        tmp_path: Path) -> None:
    core = UavCore(steering_config(tmp_path, require_autopilot_fence=True))
    await core.start()
    try:
        said = [e.message for e in core.events.recent]
        assert "autopilot fence: none (GF_ACTION does nothing)" in said
        with pytest.raises(UavError, match=r"autonomy refused: the autopilot has no fence that acts"):
            await core.execute("autonomy on")
        param = core.controller._param  # type: ignore[union-attr]
        await param.set_param_int("GF_ACTION", 3)
        await param.set_param_float("GF_MAX_HOR_DIST", 100.0)
        await core.gate.check_autopilot_failsafe()  # as at the next connect
        assert core.events.recent[-1].message == "autopilot fence: radius 100 m, then return (PX4 GF_*)"
        await core.execute("autonomy on")
        assert core.gate.enabled
    finally:
        await core.stop("test finished")


async def test_a_px4_geofence_plan_counts_as_a_fence_where_gf_action_acts_on_it(tmp_path: Path) -> None:
    core = UavCore(steering_config(tmp_path, require_autopilot_fence=True))
    await core.start()
    try:
        controller = core.controller
        param = controller._param  # type: ignore[union-attr]
        await param.set_param_int("GF_ACTION", 2)
        await core.gate.check_autopilot_failsafe()
        assert core.events.recent[-2].message == ("autopilot fence: none (GF_MAX_HOR_DIST and GF_MAX_VER_DIST are 0, "
                                                  "no geofence plan)")
        corners = [Point(47.3975, 8.5455), Point(47.3985, 8.5455), Point(47.3985, 8.5465), Point(47.3975, 8.5465)]
        await GeofenceAsync(controller._system).upload_geofence(GeofenceData(  # type: ignore[union-attr]
            polygons=[Polygon(corners, FenceType.INCLUSION)],
            circles=[Circle(Point(47.3979, 8.5461), 5.0, FenceType.EXCLUSION)]))
        await core.gate.check_autopilot_failsafe()  # as at the next connect
        assert core.events.recent[-1].message == ("autopilot fence: geofence plan (1 inclusion, 1 exclusion), then "
                                                  "hold (PX4 GF_*)")
        assert not core.gate.refusal
    finally:
        await core.stop("test finished")


class _Plan:
    def __init__(self, plan: FencePlan | None) -> None:
        self.plan = plan

    async def __call__(self) -> FencePlan:
        if self.plan is None:
            raise ControllerError("download_geofence: no answer within 10.0 s")
        return self.plan


@pytest.mark.parametrize(("values", "plan", "enabled", "summary"), [
    ({"GF_ACTION": 1, "GF_MAX_HOR_DIST": 50.0}, FencePlan(1), False, "autopilot fence: none (GF_ACTION does nothing)"),
    ({"GF_ACTION": 3, "GF_MAX_HOR_DIST": 0.0, "GF_MAX_VER_DIST": 0.0}, FencePlan(), False,
     "autopilot fence: none (GF_MAX_HOR_DIST and GF_MAX_VER_DIST are 0, no geofence plan)"),
    ({"GF_ACTION": 5, "GF_MAX_HOR_DIST": 0.0, "GF_MAX_VER_DIST": 30.0}, FencePlan(2), True,
     "autopilot fence: height 30 m, geofence plan (2 inclusion), then land (PX4 GF_*)"),
    ({"GF_ACTION": 3, "GF_MAX_HOR_DIST": 0.0, "GF_MAX_VER_DIST": 0.0}, None, False,
     "autopilot fence: none (GF_MAX_HOR_DIST and GF_MAX_VER_DIST are 0, no geofence plan; its geofence plan could "
     "not be read (download_geofence: no answer within 10.0 s))"),
    ({"GF_ACTION": 3, "GF_MAX_HOR_DIST": 80.0, "GF_MAX_VER_DIST": 0.0}, None, True,
     "autopilot fence: radius 80 m, then return (PX4 GF_*; its geofence plan could not be read "
     "(download_geofence: no answer within 10.0 s))"),
], ids=["warning only", "nothing set", "height and plan", "plan unreadable", "radius, plan unreadable"])
async def test_px4_fence_parameters_and_geofence_plan_say_whether_a_fence_acts(
        values: dict[str, float], plan: FencePlan | None, enabled: bool, summary: str) -> None:
    report = await read_fence(Autopilot.PX4, ParamAccess(_Params(**values), _bound), _Plan(plan))
    assert (report.enabled, report.summary) == (enabled, summary)
