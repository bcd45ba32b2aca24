"""Raw MAVLink through MAVSDK's MavlinkDirect plugin: mode changes, velocity setpoints, landing targets.

Why not MAVSDK's Offboard plugin: from the first ``set_velocity_body`` on, MAVSDK re-sends the last
setpoint at 20 Hz from its own thread until ``offboard.stop()``. If our event loop stalled during a
vector, the vehicle would keep flying on that setpoint. Sent through here, setpoints stop whenever
our stream stops, and the autopilot's offboard-loss failsafe takes over.
"""

from __future__ import annotations

import json
from typing import Any

from mavsdk.asyncio import MavsdkError
from mavsdk.asyncio.plugins.mavlink_direct import MavlinkDirectAsync, MavlinkMessage

MAV_CMD_DO_SET_MODE = 176
MAV_MODE_FLAG_CUSTOM_MODE_ENABLED = 1
MAV_FRAME_BODY_NED = 8
"""Velocities forward/right/down, rotated by the current heading (PX4 and ArduCopter)."""

VELOCITY_ONLY_MASK = 0b111 | (0b111 << 6) | (1 << 10)
"""type_mask: ignore position, acceleration and yaw; use velocity and yaw rate (as MAVSDK does)."""

PX4_MODES = {"OFFBOARD": (6, 0), "HOLD": (4, 3), "PRECLAND": (4, 9)}
"""PX4 (main_mode, sub_mode) for DO_SET_MODE param2/param3."""

MAV_RESULTS = {
    0: "ACCEPTED",
    1: "TEMPORARILY_REJECTED",
    2: "COMMAND_DENIED",
    3: "UNSUPPORTED",
    4: "FAILED",
    5: "IN_PROGRESS",
    6: "CANCELLED",
}
"""MAV_RESULT -> the names MAVSDK's own result enums use, so one error mapping fits both."""


class CommandAckError(MavsdkError):
    """A COMMAND_ACK other than ACCEPTED, shaped like MAVSDK's plugin errors (``.result``)."""

    def __init__(self, result: str, origin: str) -> None:
        super().__init__(result, origin)
        self.result = result
        self.origin = origin

    def __str__(self) -> str:
        return f"{self.result}; origin: {self.origin}"


def _message(name: str, target_system: int, fields: dict[str, Any]) -> MavlinkMessage:
    return MavlinkMessage(
        message_name=name,
        target_system_id=target_system,
        target_component_id=1,
        fields_json=json.dumps({"target_system": target_system, "target_component": 1, **fields}),
    )


def command_long(target_system: int, command: int, *params: float) -> MavlinkMessage:
    """COMMAND_LONG to the autopilot component with up to 7 params (the rest 0)."""
    values = [float(p) for p in params] + [0.0] * (7 - len(params))
    fields: dict[str, Any] = {"command": command, "confirmation": 0}
    fields |= {f"param{i + 1}": v for i, v in enumerate(values)}
    return _message("COMMAND_LONG", target_system, fields)


def px4_set_mode(target_system: int, mode: str) -> MavlinkMessage:
    """DO_SET_MODE with a PX4 custom mode (``"OFFBOARD"``, ``"HOLD"``)."""
    main, sub = PX4_MODES[mode]
    return command_long(target_system, MAV_CMD_DO_SET_MODE, MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, main, sub)


def velocity_body_setpoint(target_system: int, forward_ms: float, right_ms: float,
                           down_ms: float = 0.0) -> MavlinkMessage:
    """SET_POSITION_TARGET_LOCAL_NED: body velocity (``down_ms``: the height hold's correction); yaw rate 0."""
    fields = {
        "time_boot_ms": 0,
        "coordinate_frame": MAV_FRAME_BODY_NED,
        "type_mask": VELOCITY_ONLY_MASK,
        **dict.fromkeys(("x", "y", "z", "afx", "afy", "afz", "yaw", "yaw_rate"), 0.0),
        "vx": float(forward_ms),
        "vy": float(right_ms),
        "vz": float(down_ms),
    }
    return _message("SET_POSITION_TARGET_LOCAL_NED", target_system, fields)


def landing_target(target_system: int, fields: dict[str, Any]) -> MavlinkMessage:
    """LANDING_TARGET with ``fields`` (:mod:`controllers.landing_target_message`); a broadcast: no target fields."""
    return MavlinkMessage(message_name="LANDING_TARGET", target_system_id=target_system, target_component_id=1,
                          fields_json=json.dumps(fields))


def ack_result(ack: MavlinkMessage) -> str:
    """The result name in a COMMAND_ACK from ``send_command`` (``"ACCEPTED"``, ``"COMMAND_DENIED"``...)."""
    code = json.loads(ack.fields_json or "{}").get("result")
    return MAV_RESULTS.get(code, f"RESULT_{code}")


async def send_command(direct: MavlinkDirectAsync, command: MavlinkMessage) -> None:
    """Send a command and wait for its final ACK.

    Raises:
        CommandAckError: the ACK was not ACCEPTED (MAVSDK's own errors for no ACK at all).
    """
    result = ack_result(await direct.send_command(command))
    if result != "ACCEPTED":
        raise CommandAckError(result, json.loads(command.fields_json)["command"])
