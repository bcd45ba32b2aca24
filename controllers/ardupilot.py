"""ArduCopter quirks, each a small function with the measured fact that requires it.

Measured against ArduCopter 4.8-dev SITL with MAVSDK 4.1 (see ARCHITECTURE.md, "Autopilot facts").
"""

from __future__ import annotations

import json
import logging
import math

from mavsdk.asyncio.plugins.mavlink_direct import MavlinkDirectAsync, MavlinkMessage
from mavsdk.asyncio.plugins.param import ParamAsync

from uav_tui.errors import CommandDenied

logger = logging.getLogger(__name__)

COPTER_MODES = {"GUIDED": 4, "LOITER": 5, "RTL": 6, "CIRCLE": 7, "LAND": 9, "BRAKE": 17}
"""ArduCopter custom_mode numbers."""

MAV_CMD_DO_SET_MODE = 176
MAV_MODE_FLAG_CUSTOM_MODE_ENABLED = 1
MAV_DATA_STREAM_ALL = 0
MAV_RESULT_NAMES = {0: "ACCEPTED", 1: "TEMPORARILY_REJECTED", 2: "DENIED", 3: "UNSUPPORTED", 4: "FAILED"}

STREAM_RATE_HZ = 10
"""Rate asked for with REQUEST_DATA_STREAM (all streams), as MAVProxy and Mission Planner do."""

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
    """COMMAND_LONG MAV_CMD_DO_SET_MODE with an ArduCopter custom mode (``"GUIDED"``, ``"CIRCLE"``...)."""
    fields = {
        "target_system": target_system,
        "target_component": 1,
        "command": MAV_CMD_DO_SET_MODE,
        "confirmation": 0,
        "param1": MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
        "param2": COPTER_MODES[mode],
        "param3": 0,
        "param4": 0,
        "param5": 0,
        "param6": 0,
        "param7": 0,
    }
    return MavlinkMessage(
        message_name="COMMAND_LONG",
        target_system_id=target_system,
        target_component_id=1,
        fields_json=json.dumps(fields),
    )


def ack_result(ack: MavlinkMessage) -> str:
    """The MAV_RESULT name in a COMMAND_ACK returned by ``send_command``."""
    code = json.loads(ack.fields_json or "{}").get("result")
    return MAV_RESULT_NAMES.get(code, f"RESULT_{code}")


async def set_mode(direct: MavlinkDirectAsync, target_system: int, mode: str, *, command: str) -> None:
    """Switch ArduCopter to ``mode``; raises CommandDenied with the autopilot's answer.

    Fact: re-arming after RTL/land through MAVSDK 4 fails ("Brake mode not armable") unless the
    mode is changed to GUIDED first.
    """
    ack = await direct.send_command(set_mode_command(target_system, mode))
    result = ack_result(ack)
    if result != "ACCEPTED":
        message = f"{command}: switching to {mode} refused ({result})"
        raise CommandDenied(message, command=command, result=result)


async def request_streams(direct: MavlinkDirectAsync, target_system: int) -> None:
    """Ask for every data stream (see :func:`request_data_streams_message`)."""
    await direct.send_message(request_data_streams_message(target_system))


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
        message = "do_orbit: cannot set the circle radius parameter"
        raise CommandDenied(message, command="do_orbit", result="FAILED")
    await params.set_param_float("CIRCLE_RATE", circle_rate_deg_s(radius_m, velocity_ms))
    await set_mode(direct, target_system, "CIRCLE", command="do_orbit")
