"""ArduCopter quirks, each a small function with the measured fact that requires it.

Measured against ArduCopter 4.8-dev SITL with MAVSDK 4.1 (see docs/flight-controllers.md, "Measured autopilot facts").
"""

from __future__ import annotations

import json
import logging
import math

from mavsdk.asyncio.plugins.mavlink_direct import MavlinkDirectAsync, MavlinkMessage
from mavsdk.asyncio.plugins.param import ParamAsync

from controllers.mavsdk.mavlink_commands import (
    MAV_CMD_DO_SET_MODE,
    MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
    CommandAckError,
    command_long,
    send_command,
    velocity_body_setpoint,
)

logger = logging.getLogger(__name__)

COPTER_MODES = {"GUIDED": 4, "LOITER": 5, "RTL": 6, "CIRCLE": 7, "LAND": 9, "BRAKE": 17}
"""ArduCopter custom_mode numbers."""

MAV_DATA_STREAM_ALL = 0
STREAM_RATE_HZ = 10
"""Rate asked for with REQUEST_DATA_STREAM (all streams), as MAVProxy and Mission Planner do."""

MAV_CMD_NAV_TAKEOFF = 22
DEFAULT_TAKEOFF_ALT_M = 2.5
"""Used when take-off is asked for without an altitude (PX4 has MIS_TAKEOFF_ALT; ArduCopter needs one)."""

CIRCLE_RADIUS_PARAMS = (("CIRCLE_RADIUS_M", 1.0), ("CIRCLE_RADIUS", 100.0))
"""(name, units per metre): 4.8 renamed parameters (RTL_ALT -> RTL_ALT_M); try the new name first."""


def request_data_streams_message(target_system: int, rate_hz: int = STREAM_RATE_HZ) -> MavlinkMessage:
    """REQUEST_DATA_STREAM for all streams.

    Fact: ArduCopter sends no telemetry until a client asks for it; code that waits for a
    position without asking hangs.
    """
    fields = {
        "target_system": target_system,
        "target_component": 1,
        "req_stream_id": MAV_DATA_STREAM_ALL,
        "req_message_rate": rate_hz,
        "start_stop": 1,
    }
    return MavlinkMessage(
        message_name="REQUEST_DATA_STREAM",
        target_system_id=target_system,
        target_component_id=1,
        fields_json=json.dumps(fields),
    )


def set_mode_command(target_system: int, mode: str) -> MavlinkMessage:
    """DO_SET_MODE with an ArduCopter custom mode (``"GUIDED"``, ``"LOITER"``, ``"CIRCLE"``...)."""
    return command_long(target_system, MAV_CMD_DO_SET_MODE, MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, COPTER_MODES[mode])


async def set_mode(direct: MavlinkDirectAsync, target_system: int, mode: str) -> None:
    """Switch ArduCopter to ``mode``; raises CommandAckError with the autopilot's answer.

    Fact: re-arming after RTL/land through MAVSDK 4 fails ("Brake mode not armable") unless the
    mode is changed to GUIDED first.
    """
    await send_command(direct, set_mode_command(target_system, mode))


async def hold(direct: MavlinkDirectAsync, target_system: int) -> None:
    """Stop and hold position, altitude and heading whatever the RC sticks say: GUIDED, zero velocity.

    Fact: LOITER flies the RC throttle stick; at its minimum (SITL's default
    input, a transmitter left at idle) it descends at the pilot's maximum rate (measured 9.98 m -> 6.6 m
    at up to 2.31 m/s). GUIDED ignores the sticks: entering it, or a zero velocity target, brakes to a
    stop and keeps that point and altitude (ArduCopter's own ``ModeGuided::hold_position``), and a target
    that lapses after GUID_TIMEOUT is zeroed, which holds too. GUIDED also keeps re-arming possible
    (BRAKE would hold, but MAVSDK 4 cannot arm from it). Switching to GUIDED when already there changes
    nothing, so the zero target is what stops a take-off or a vector.
    """
    await set_mode(direct, target_system, "GUIDED")
    await direct.send_message(velocity_body_setpoint(target_system, 0.0, 0.0))


def takeoff_command(target_system: int, altitude_m: float) -> MavlinkMessage:
    """NAV_TAKEOFF; ArduCopter reads param7 as metres above home."""
    return command_long(target_system, MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, altitude_m)


async def takeoff(direct: MavlinkDirectAsync, target_system: int, altitude_m: float) -> None:
    """Take off in GUIDED (the caller switched to GUIDED and armed).

    Sent raw rather than through MAVSDK's Action, whose take-off altitude is a PX4 parameter
    (MIS_TAKEOFF_ALT) that ArduCopter does not have.
    """
    await send_command(direct, takeoff_command(target_system, altitude_m))


async def request_streams(direct: MavlinkDirectAsync, target_system: int) -> None:
    """Ask for every data stream (see :func:`request_data_streams_message`)."""
    await direct.send_message(request_data_streams_message(target_system))


CIRCLE_FLIES_THE_THROTTLE = ("ArduCopter orbits in CIRCLE mode, which climbs and sinks with the RC throttle stick "
                             "as LOITER does: with no pilot holding it at mid-stick the orbit sinks; 'hold' ends it")
"""Said at every orbit (ArduCopter's ``mode_circle.cpp`` takes its climb rate from the pilot's throttle)."""


def circle_rate_deg_s(radius_m: float, velocity_ms: float) -> float:
    """CIRCLE_RATE (deg/s, positive = clockwise) for a tangential speed on a radius."""
    return math.degrees(velocity_ms / radius_m)


async def start_circle(
    direct: MavlinkDirectAsync, params: ParamAsync, target_system: int, radius_m: float, velocity_ms: float
) -> None:
    """Orbit by CIRCLE mode: set the radius and rate parameters, then switch to CIRCLE.

    Fact: ArduCopter answers MAV_CMD_DO_ORBIT with UNSUPPORTED. Its CIRCLE mode circles a centre
    ``radius`` ahead of the vehicle.
    """
    for name, per_metre in CIRCLE_RADIUS_PARAMS:
        try:
            await params.set_param_float(name, radius_m * per_metre)
            break
        except Exception as exc:  # noqa: BLE001 - the other name may exist
            logger.debug("ArduCopter has no %s (%s)", name, exc)
    else:
        raise CommandAckError("FAILED", "set CIRCLE_RADIUS_M / CIRCLE_RADIUS")
    await params.set_param_float("CIRCLE_RATE", circle_rate_deg_s(radius_m, velocity_ms))
    await set_mode(direct, target_system, "CIRCLE")
    logger.warning(CIRCLE_FLIES_THE_THROTTLE)
