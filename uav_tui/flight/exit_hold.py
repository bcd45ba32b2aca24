"""What happens to the vehicle when uav-tui exits: held, unless something else is flying it on purpose."""

from __future__ import annotations

import asyncio

from controllers.base import FlightController
from uav_tui.errors import KNOWN_ERRORS
from uav_tui.events import EventLog
from uav_tui.flight.autonomy import own_modes

LEFT_ALONE_AT_EXIT = frozenset({"LAND", "PRECISION_LAND", "RETURN_TO_LAUNCH", "SMART_RTL", "MISSION", "MANUAL",
                                "STABILIZED", "ALTCTL", "ACRO", "RATTITUDE"})
"""Flight modes (:mod:`controllers.flight_modes` names) a hold before exit would interrupt: the vehicle landing or
returning by itself (the operator's ``land``/``rtl``/``precland`` or a failsafe), a mission, a pilot flying by
hand. Exit holds the vehicle in any other mode, where something uav-tui started (a vector, an orbit, a takeoff) may
be flying it."""


def mode_left_at_exit(mode: str | None, controller: FlightController | None, handed_over: str | None) -> str | None:
    """The mode the vehicle is left in at exit (:data:`LEFT_ALONE_AT_EXIT`), or None: it is held first.

    ``mode`` is the one the vehicle reports. Right after uav-tui's own ``land`` or ``rtl`` (``handed_over``)
    the autopilot may not have reported its new mode yet (PX4 says it in its next heartbeat, up to a second
    later): that command's mode counts, unless vectors fly the vehicle again.
    """
    if mode in LEFT_ALONE_AT_EXIT or (mode == "HOLD" and mode not in own_modes(controller)):
        return mode  # HOLD not of the platform's making: ArduCopter's LOITER or BRAKE, a pilot's
    if handed_over is not None and not (controller is not None and controller.vector_active):
        return handed_over
    return None


async def hold_before_exit(controller: FlightController, left_in: str | None, events: EventLog) -> None:
    """Hold the vehicle (5 s at most) unless it is ``left_in`` a mode of its own; say which."""
    if left_in:
        events.emit("info", "platform", f"vehicle left in {left_in} mode at exit: a hold would interrupt it")
        return
    try:
        await asyncio.wait_for(controller.hold(), 5)
        events.emit("info", "platform", "vehicle put in hold before exit")
    except KNOWN_ERRORS + (TimeoutError,) as exc:
        events.emit("error", "platform", f"hold before exit failed: {exc!r}")
