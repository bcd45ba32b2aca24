"""Which autopilot the simulated vehicle plays: PX4 (the default) or ArduCopter (``--autopilot ardupilot``).

The ArduCopter dialect covers what the platform relies on and what it must not: HEARTBEAT as
ArduPilot (MAVSDK then maps GUIDED to OFFBOARD and LOITER/BRAKE to HOLD), ArduCopter mode numbers,
arming and NAV_TAKEOFF (metres above home) in GUIDED, GUIDED velocity and position targets that lapse
after GUID_TIMEOUT into a hold, and an RC throttle stick that LOITER follows: at SITL's default input
(1000, the minimum) LOITER descends at the pilot's maximum rate, as ArduCopter does. Not simulated:
CIRCLE and the other stick-flown modes (DO_SET_MODE answers DENIED), stream requests (it always streams).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from pymavlink.dialects.v20 import common as mavlink

from controllers.autopilots import Autopilot
from controllers.sim import ardupilot_modes, px4_modes
from controllers.sim.guidance import Mode

M = mavlink


class ModeEncoding(Protocol):
    """How flight modes travel in HEARTBEAT and DO_SET_MODE (:mod:`px4_modes`, :mod:`ardupilot_modes`)."""

    def custom_mode(self, mode: Mode) -> int: ...
    def base_mode(self, mode: Mode, armed: bool) -> int: ...
    def mode_from_command(self, param2: int, param3: int) -> Mode | None: ...


@dataclass(frozen=True, slots=True)
class Dialect:
    """One autopilot's way of saying things."""

    name: Autopilot
    autopilot: int
    """HEARTBEAT.autopilot (MAV_AUTOPILOT_*)."""
    modes: ModeEncoding
    capabilities: int
    """AUTOPILOT_VERSION.capabilities."""
    sw_version: int
    """AUTOPILOT_VERSION.flight_sw_version."""
    takeoff_above_home: bool
    """NAV_TAKEOFF param7 is metres above home (ArduCopter), not AMSL (PX4)."""

    @property
    def ardupilot(self) -> bool:
        return self.name is Autopilot.ARDUPILOT


_COMMON_CAPABILITIES = (
    M.MAV_PROTOCOL_CAPABILITY_MISSION_FLOAT
    | M.MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT
    | M.MAV_PROTOCOL_CAPABILITY_MISSION_INT
    | M.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
    | M.MAV_PROTOCOL_CAPABILITY_SET_ATTITUDE_TARGET
    | M.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_LOCAL_NED
    | M.MAV_PROTOCOL_CAPABILITY_MAVLINK2
)

DIALECTS = {
    Autopilot.PX4: Dialect(Autopilot.PX4, M.MAV_AUTOPILOT_PX4, px4_modes,
                           _COMMON_CAPABILITIES | M.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE,
                           (1 << 24) | (16 << 16) | (0 << 8) | 255,  # PX4 v1.16.0 release
                           takeoff_above_home=False),
    Autopilot.ARDUPILOT: Dialect(Autopilot.ARDUPILOT, M.MAV_AUTOPILOT_ARDUPILOTMEGA, ardupilot_modes,
                                 _COMMON_CAPABILITIES | M.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_C_CAST,
                                 (4 << 24) | (8 << 16) | (0 << 8) | 0,  # ArduCopter 4.8.0-dev
                                 takeoff_above_home=True),
}
"""The dialects by ``--autopilot`` name."""
