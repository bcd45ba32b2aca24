"""ArduCopter's flight-mode encoding (the simulator's ``ardupilot`` dialect): HEARTBEAT.custom_mode is the
mode number, DO_SET_MODE carries it in param2. The same functions as :mod:`controllers.sim.px4_modes`."""

from __future__ import annotations

from pymavlink.dialects.v20 import common as mavlink

from controllers.sim.guidance import Mode

GUIDED, LOITER, RTL, LAND, BRAKE = 4, 5, 6, 9, 17
"""ArduCopter custom_mode numbers of the modes the simulator has."""

_TO_COPTER: dict[Mode, int] = {
    Mode.GUIDED: GUIDED,
    Mode.TAKEOFF: GUIDED,  # ArduCopter takes off inside GUIDED
    Mode.LOITER: LOITER,
    Mode.RTL: RTL,
    Mode.LAND: LAND,
    Mode.HOLD: BRAKE,  # brake to a stop and keep that point, as PX4's HOLD
}
_FROM_COPTER = {GUIDED: Mode.GUIDED, LOITER: Mode.LOITER, RTL: Mode.RTL, LAND: Mode.LAND, BRAKE: Mode.HOLD}


def custom_mode(mode: Mode) -> int:
    """HEARTBEAT.custom_mode for ``mode``."""
    return _TO_COPTER[mode]


def mode_from_command(number: int, _sub: int) -> Mode | None:
    """The mode DO_SET_MODE asks for (param2: the ArduCopter mode number), or None if the sim lacks it."""
    return _FROM_COPTER.get(number)


def base_mode(mode: Mode, armed: bool) -> int:
    """HEARTBEAT.base_mode flags the way ArduCopter sets them."""
    flags = (mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED
             | mavlink.MAV_MODE_FLAG_GUIDED_ENABLED)
    if armed:
        flags |= mavlink.MAV_MODE_FLAG_SAFETY_ARMED
    return flags
