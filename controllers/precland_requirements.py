"""What each autopilot needs to start a precision landing on the companion's LANDING_TARGET.

* **ArduPilot**: ``PLND_ENABLED = 1`` and ``PLND_TYPE = 1`` (companion computer), both read before LAND is asked
  for; the autopilot reads them at boot, so a wrong value is reported (set it and reboot), never changed here.
  In LAND it then flies over the target while it descends.
* **PX4**: its Precision Land flight mode (``AUTO_PRECLAND``, DO_SET_MODE main 4 sub 9): it flies over the
  target (``landing_target_pose``, from LANDING_TARGET) and descends onto it. ``MAV_CMD_NAV_LAND`` with param 2
  (precision "opportunistic"/"required") is read only in a mission: outside one, PX4 v1.16's Commander turns it
  into plain LAND at the current position (measured on its SITL: it came down 3 m from the target).
  MAVSDK 4 has no name for that mode (it says ``UNKNOWN``); the controller names it ``PRECISION_LAND`` from the
  HEARTBEAT (:mod:`controllers.flight_modes`).
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

from controllers.autopilots import Autopilot
from controllers.errors import ControllerError

LANDING_MODES = {Autopilot.ARDUPILOT: frozenset({"LAND"}), Autopilot.PX4: frozenset({"PRECISION_LAND"})}
"""The flight modes (:mod:`controllers.flight_modes` names) each autopilot reports while it lands precisely."""

ARDUPILOT_PARAMS = {"PLND_ENABLED": (1, "precision landing on"), "PLND_TYPE": (1, "companion computer: "
                                                                                "LANDING_TARGET from uav-tui")}
"""ArduPilot parameter -> (the value precision landing from uav-tui needs, what it means)."""

ReadInt = Callable[[str], Awaitable[Any]]
"""``read(name)``: the autopilot's integer parameter ``name``, raising ControllerError when it can't be read."""


class PrecisionLandingError(ControllerError):
    """The autopilot is not set up for a precision landing (the message names the parameter and the value)."""


async def check_ardupilot_params(read: ReadInt) -> dict[str, int]:
    """Read ArduPilot's PLND parameters; returns them when each has the value :data:`ARDUPILOT_PARAMS` names.

    Raises:
        PrecisionLandingError: a parameter is missing (no precision landing in this firmware) or has another value.
    """
    found: dict[str, int] = {}
    for name, (wanted, meaning) in ARDUPILOT_PARAMS.items():
        try:
            value = int(await read(name))
        except ControllerError as exc:
            raise PrecisionLandingError(f"precland: the autopilot has no {name} parameter ({exc}): its firmware "
                                        "has no precision landing") from exc
        if value != wanted:
            raise PrecisionLandingError(f"precland: {name} = {value}, precision landing needs {name} = {wanted} "
                                        f"({meaning}); set it and reboot the autopilot")
        found[name] = value
    return found
