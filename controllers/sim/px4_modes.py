"""PX4's flight-mode encoding in HEARTBEAT.custom_mode: ``main_mode << 16 | sub_mode << 24``."""

from __future__ import annotations

from pymavlink.dialects.v20 import common as mavlink

from controllers.sim.guidance import Mode

MAIN_MANUAL, MAIN_POSCTL, MAIN_AUTO, MAIN_OFFBOARD = 1, 3, 4, 6
"""PX4_CUSTOM_MAIN_MODE values the simulator uses."""

_TO_PX4: dict[Mode, tuple[int, int]] = {
    Mode.MANUAL: (MAIN_MANUAL, 0),
    Mode.POSCTL: (MAIN_POSCTL, 0),
    Mode.ORBIT: (MAIN_POSCTL, 1),
    Mode.TAKEOFF: (MAIN_AUTO, 2),
    Mode.HOLD: (MAIN_AUTO, 3),
    Mode.RTL: (MAIN_AUTO, 5),
    Mode.LAND: (MAIN_AUTO, 6),
    Mode.PRECLAND: (MAIN_AUTO, 9),
    Mode.OFFBOARD: (MAIN_OFFBOARD, 0),
}
_FROM_PX4 = {v: k for k, v in _TO_PX4.items()}


def custom_mode(mode: Mode) -> int:
    """HEARTBEAT.custom_mode for ``mode``."""
    main, sub = _TO_PX4[mode]
    return (main << 16) | (sub << 24)


def mode_from_command(main: int, sub: int) -> Mode | None:
    """The mode DO_SET_MODE asks for (param2 main, param3 sub), or None if the sim lacks it."""
    if (main == MAIN_POSCTL and sub == 0) or main == MAIN_MANUAL:
        return _FROM_PX4[(main, 0)]
    return _FROM_PX4.get((main, sub))


def base_mode(mode: Mode, armed: bool) -> int:
    """HEARTBEAT.base_mode flags the way PX4 sets them."""
    flags = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED
    if mode in (Mode.MANUAL, Mode.POSCTL, Mode.ORBIT):
        flags |= mavlink.MAV_MODE_FLAG_MANUAL_INPUT_ENABLED
    if mode != Mode.MANUAL:
        flags |= mavlink.MAV_MODE_FLAG_GUIDED_ENABLED
    if _TO_PX4[mode][0] in (MAIN_AUTO, MAIN_OFFBOARD):
        flags |= mavlink.MAV_MODE_FLAG_AUTO_ENABLED
    if armed:
        flags |= mavlink.MAV_MODE_FLAG_SAFETY_ARMED
    return flags
