"""The autopilot's own geofence, read at connect: whether one is set up that would act when crossed.

The platform's envelope (``uav_tui.flight.envelope``) keeps the processor's vectors in; the autopilot's fence is
the next line, and it holds when the platform is dead. On a companion-computer flight nobody has often set it up.
Read: PX4's ``GF_ACTION`` (0 none, 1 warning only; 2 hold, 3 return, 4 terminate, 5 land act) with
``GF_MAX_HOR_DIST`` / ``GF_MAX_VER_DIST`` (0 = no limit) and its geofence plan (polygons and circles uploaded as a
mission of type fence, downloaded; ``GF_ACTION`` acts on them too); ArduPilot's ``FENCE_ENABLE`` and
``FENCE_ACTION`` (0 reports only) with ``FENCE_TYPE`` (bits: 1 ceiling, 2 circle, 4 polygon, 8 floor),
``FENCE_RADIUS`` and ``FENCE_ALT_MAX``.
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Awaitable, Callable
from dataclasses import dataclass

from controllers.autopilots import Autopilot
from controllers.errors import ControllerError
from controllers.failsafe import ParamAccess

PX4_ACTING = {2: "hold", 3: "return", 4: "terminate", 5: "land"}
"""GF_ACTION values that do something at the fence (1 only warns)."""


@dataclass(frozen=True, slots=True)
class FenceReport:
    """Whether the autopilot has a fence that acts, and one line that says what was read."""

    enabled: bool
    summary: str


@dataclass(frozen=True, slots=True)
class FencePlan:
    """A geofence plan on the autopilot: how many polygons and circles keep the vehicle in, and out."""

    inclusion: int = 0
    exclusion: int = 0

    def describe(self) -> str:
        areas = [f"{n} {what}" for n, what in ((self.inclusion, "inclusion"), (self.exclusion, "exclusion")) if n]
        return f"geofence plan ({', '.join(areas)})" if areas else ""


PlanReader = Callable[[], Awaitable[FencePlan]]
"""Downloads the autopilot's geofence plan (raises ControllerError when it cannot)."""


async def read_fence(autopilot: Autopilot, params: ParamAccess, plan: PlanReader | None = None) -> FenceReport:
    """Read the fence of a PX4 (its parameters and, with ``plan``, its geofence plan) or ArduPilot autopilot (its
    parameters); any other: not known."""
    try:
        if autopilot is Autopilot.PX4:
            return await _px4(params, plan)
        if autopilot is Autopilot.ARDUPILOT:
            return await _ardupilot(params)
    except ControllerError as exc:
        return FenceReport(False, f"autopilot fence: unknown, a parameter could not be read ({exc})")
    return FenceReport(False, f"autopilot fence: unknown (cannot read the fence of an {autopilot} autopilot)")


async def _px4(params: ParamAccess, plan: PlanReader | None) -> FenceReport:
    action = int(await params.read("GF_ACTION", integer=True))
    if action not in PX4_ACTING:
        return FenceReport(False, "autopilot fence: none (GF_ACTION does nothing)")
    horizontal = await params.read("GF_MAX_HOR_DIST", integer=False)
    vertical = await params.read("GF_MAX_VER_DIST", integer=False)
    limits = [f"{what} {value:g} m" for what, value in (("radius", horizontal), ("height", vertical)) if value > 0]
    unread = "" if plan is not None else "; its geofence plan cannot be read here"
    if plan is not None:
        try:
            described = (await plan()).describe()
            limits += [described] if described else []
        except ControllerError as exc:
            unread = f"; its geofence plan could not be read ({exc})"
    if not limits:
        return FenceReport(False, f"autopilot fence: none (GF_MAX_HOR_DIST and GF_MAX_VER_DIST are 0, no geofence "
                                  f"plan{unread})")
    return FenceReport(True, f"autopilot fence: {', '.join(limits)}, then {PX4_ACTING[action]} (PX4 GF_*{unread})")


async def _ardupilot(params: ParamAccess) -> FenceReport:
    if int(await params.read("FENCE_ENABLE", integer=True)) != 1:
        return FenceReport(False, "autopilot fence: none (FENCE_ENABLE is 0)")
    if int(await params.read("FENCE_ACTION", integer=True)) == 0:
        return FenceReport(False, "autopilot fence: reports only (FENCE_ACTION is 0)")
    kinds = int(await params.read("FENCE_TYPE", integer=True))
    parts = [what for bit, what in ((2, "circle"), (4, "polygon"), (1, "ceiling"), (8, "floor")) if kinds & bit]
    if kinds & 2:
        parts[0] = f"circle {await params.read('FENCE_RADIUS', integer=False):g} m"
    if kinds & 1:
        parts[parts.index("ceiling")] = f"ceiling {await params.read('FENCE_ALT_MAX', integer=False):g} m"
    return FenceReport(bool(parts), f"autopilot fence: {', '.join(parts) or 'no kind set (FENCE_TYPE 0)'} "
                                    "(ArduPilot FENCE_*)")


class ReadsFence:
    """``check_fence`` (:class:`controllers.base.FenceCheck`) for a MAVLink controller, from its autopilot's kind
    and its bounded parameter calls."""

    autopilot: Autopilot

    @abstractmethod
    def _params(self) -> ParamAccess:
        """Parameter reads and writes, each bounded in time."""

    @abstractmethod
    async def _fence_plan(self) -> FencePlan:
        """The autopilot's geofence plan, downloaded within a bounded time (ControllerError when it is not)."""

    async def check_fence(self) -> FenceReport:
        """Whether the autopilot has a geofence that acts when crossed."""
        return await read_fence(self.autopilot, self._params(), self._fence_plan)
