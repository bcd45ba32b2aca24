"""Flight-mode names decoded from HEARTBEAT (``autopilot``, ``type``, ``base_mode``, ``custom_mode``).

MAVSDK 4 names a few modes (:data:`MAVSDK_NAMES`) and reports every other one as ``UNKNOWN``: PX4's Precision Land
and a pilot's switch from it to another unnamed mode would both read ``UNKNOWN``. :func:`decode` names every mode:

* a mode MAVSDK names gets MAVSDK's name (PX4 AUTO_LOITER and ArduCopter LOITER are both ``HOLD``), so the two
  sources agree wherever both speak;
* a mode MAVSDK leaves ``UNKNOWN`` gets the autopilot's own name (PX4: ``PRECISION_LAND``, main 4 sub 9, from
  px4_custom_mode.h; ArduCopter: ``SMART_RTL``, custom_mode 21);
* a number in neither table gets an explicit name built from it (``PX4_MAIN4_SUB12``, ``ARDUCOPTER_MODE99``), one
  per distinct mode, never one catch-all.
"""

from __future__ import annotations

MAV_MODE_FLAG_CUSTOM_MODE_ENABLED = 1
"""HEARTBEAT.base_mode bit: ``custom_mode`` holds the autopilot's own mode number."""

MAV_AUTOPILOT_ARDUPILOTMEGA, MAV_AUTOPILOT_PX4 = 3, 12
"""HEARTBEAT.autopilot values."""

MAV_TYPE_FIXED_WING, MAV_TYPE_GROUND_ROVER, MAV_TYPE_SURFACE_BOAT = 1, 10, 11
"""HEARTBEAT.type values whose ArduPilot firmware (Plane, Rover) numbers its modes differently from ArduCopter."""

MAVSDK_NAMES = frozenset({"READY", "TAKEOFF", "HOLD", "MISSION", "RETURN_TO_LAUNCH", "LAND", "OFFBOARD", "FOLLOW_ME",
                          "MANUAL", "ALTCTL", "POSCTL", "ACRO", "STABILIZED", "RATTITUDE"})
"""MAVSDK 4's telemetry FlightMode names other than ``UNKNOWN``."""

PX4_MAIN_MODES: dict[int, str] = {1: "MANUAL", 2: "ALTCTL", 3: "POSCTL", 5: "ACRO", 6: "OFFBOARD", 7: "STABILIZED",
                                  8: "RATTITUDE", 9: "SIMPLE", 10: "TERMINATION"}
"""PX4_CUSTOM_MAIN_MODE -> name, for the main modes whose sub mode does not change the name (MAVSDK names POSCTL's
orbit and slow sub modes POSCTL too)."""

PX4_AUTO_SUB_MODES: dict[int, str] = {
    1: "READY", 2: "TAKEOFF", 3: "HOLD", 4: "MISSION", 5: "RETURN_TO_LAUNCH", 6: "LAND", 8: "FOLLOW_ME",
    9: "PRECISION_LAND", 10: "VTOL_TAKEOFF",
    **{11 + n: f"EXTERNAL{n + 1}" for n in range(8)},
}
"""PX4_CUSTOM_SUB_MODE_AUTO_* -> name, inside main mode 4 (AUTO)."""

PX4_MAIN_AUTO = 4

ARDUCOPTER_MODES: dict[int, str] = {
    0: "STABILIZED", 1: "ACRO", 2: "ALTCTL", 3: "MISSION", 4: "OFFBOARD", 5: "HOLD", 6: "RETURN_TO_LAUNCH",
    7: "CIRCLE", 9: "LAND", 11: "DRIFT", 13: "SPORT", 14: "FLIP", 15: "AUTOTUNE", 16: "POSCTL", 17: "BRAKE",
    18: "THROW", 19: "AVOID_ADSB", 20: "GUIDED_NOGPS", 21: "SMART_RTL", 22: "HOLD", 23: "FOLLOW_ME", 24: "ZIGZAG",
    25: "SYSTEMID", 26: "AUTOROTATE", 27: "RETURN_TO_LAUNCH", 28: "TURTLE", 29: "RATE_ACRO",
}
"""ArduCopter's custom_mode numbers -> name: MAVSDK's where it has one (GUIDED is OFFBOARD, LOITER and FLOWHOLD
HOLD, POSHOLD POSCTL, AUTO MISSION, RTL and AUTO_RTL RETURN_TO_LAUNCH), ArduCopter's own otherwise."""


def decode(autopilot: int, vehicle_type: int, base_mode: int, custom_mode: int) -> str:
    """The flight mode a HEARTBEAT with these fields reports (see the module docstring for the names)."""
    if not base_mode & MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
        return f"BASE_MODE{base_mode}"
    if autopilot == MAV_AUTOPILOT_PX4:
        return decode_px4(custom_mode)
    if autopilot == MAV_AUTOPILOT_ARDUPILOTMEGA:
        if vehicle_type in (MAV_TYPE_FIXED_WING, MAV_TYPE_GROUND_ROVER, MAV_TYPE_SURFACE_BOAT):
            return f"ARDUPILOT_TYPE{vehicle_type}_MODE{custom_mode}"
        return ARDUCOPTER_MODES.get(custom_mode, f"ARDUCOPTER_MODE{custom_mode}")
    return f"AUTOPILOT{autopilot}_MODE{custom_mode}"


def decode_px4(custom_mode: int) -> str:
    """PX4's mode from ``custom_mode`` (main mode in bits 16-23, sub mode in bits 24-31, px4_custom_mode.h)."""
    main, sub = (custom_mode >> 16) & 0xFF, (custom_mode >> 24) & 0xFF
    name = PX4_AUTO_SUB_MODES.get(sub) if main == PX4_MAIN_AUTO else PX4_MAIN_MODES.get(main)
    return name or f"PX4_MAIN{main}_SUB{sub}"
