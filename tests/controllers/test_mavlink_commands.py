"""The raw MAVLink the controller sends (PX4 mode changes, setpoints, ArduCopter quirks)."""

from __future__ import annotations

import json
import math

import pytest
from mavsdk.asyncio.plugins.mavlink_direct import MavlinkMessage

from controllers.mavsdk import ardupilot
from controllers.mavsdk.mavlink_commands import ack_result, px4_set_mode, velocity_body_setpoint


def fields(msg: MavlinkMessage) -> dict[str, float]:
    return json.loads(msg.fields_json)


@pytest.mark.parametrize(("mode", "number"), [("GUIDED", 4), ("LOITER", 5), ("CIRCLE", 7), ("LAND", 9)])
def test_ardupilot_set_mode_is_do_set_mode_with_the_custom_mode(mode: str, number: int) -> None:
    msg = ardupilot.set_mode_command(7, mode)
    assert msg.message_name == "COMMAND_LONG"
    assert (msg.target_system_id, msg.target_component_id) == (7, 1)
    f = fields(msg)
    assert (f["command"], f["param1"], f["param2"], f["target_system"]) == (176, 1, number, 7)


@pytest.mark.parametrize(("mode", "main", "sub"), [("OFFBOARD", 6, 0), ("HOLD", 4, 3)])
def test_px4_set_mode_carries_main_and_sub_mode(mode: str, main: int, sub: int) -> None:
    f = fields(px4_set_mode(1, mode))
    assert (f["command"], f["param1"], f["param2"], f["param3"]) == (176, 1, main, sub)


def test_velocity_setpoint_is_body_frame_velocity_with_yaw_rate_zero() -> None:
    msg = velocity_body_setpoint(1, 0.5, -0.25)
    f = fields(msg)
    assert msg.message_name == "SET_POSITION_TARGET_LOCAL_NED"
    assert f["coordinate_frame"] == 8  # MAV_FRAME_BODY_NED
    assert (f["vx"], f["vy"], f["vz"], f["yaw_rate"]) == (0.5, -0.25, 0.0, 0.0)
    ignored = {0: "x", 1: "y", 2: "z", 6: "afx", 7: "afy", 8: "afz", 10: "yaw"}
    used = {3: "vx", 4: "vy", 5: "vz", 11: "yaw_rate"}
    assert all(f["type_mask"] & (1 << bit) for bit in ignored)
    assert not any(f["type_mask"] & (1 << bit) for bit in used)


def test_ardupilot_takeoff_altitude_is_param7() -> None:
    f = fields(ardupilot.takeoff_command(1, 4.0))
    assert (f["command"], f["param7"], f["param1"]) == (22, 4.0, 0.0)


def test_request_data_streams_asks_for_all_streams() -> None:
    assert fields(ardupilot.request_data_streams_message(3)) == {
        "target_system": 3,
        "target_component": 1,
        "req_stream_id": 0,
        "req_message_rate": ardupilot.STREAM_RATE_HZ,
        "start_stop": 1,
    }


@pytest.mark.parametrize(
    ("result", "name"),
    [
        (0, "ACCEPTED"),
        (2, "COMMAND_DENIED"),
        (3, "UNSUPPORTED"),
        (1, "TEMPORARILY_REJECTED"),
        (9, "RESULT_9"),
    ],
)
def test_ack_result_names(result: int, name: str) -> None:
    ack = MavlinkMessage(message_name="COMMAND_ACK", fields_json=json.dumps({"command": 176, "result": result}))
    assert ack_result(ack) == name


def test_circle_rate_gives_the_tangential_speed() -> None:
    rate = ardupilot.circle_rate_deg_s(5.0, 2.0)
    assert math.radians(rate) * 5.0 == pytest.approx(2.0)
