"""ArduCopter quirks: the MAVLink messages the controller sends (no ArduPilot SITL on this machine)."""

from __future__ import annotations

import json
import math

import pytest
from mavsdk.asyncio.plugins.mavlink_direct import MavlinkMessage

from controllers import ardupilot


@pytest.mark.parametrize(("mode", "number"), [("GUIDED", 4), ("LOITER", 5), ("CIRCLE", 7), ("LAND", 9)])
def test_set_mode_is_do_set_mode_with_the_custom_mode(mode: str, number: int) -> None:
    msg = ardupilot.set_mode_command(7, mode)
    fields = json.loads(msg.fields_json)
    assert msg.message_name == "COMMAND_LONG"
    assert (msg.target_system_id, msg.target_component_id) == (7, 1)
    assert fields["command"] == 176  # MAV_CMD_DO_SET_MODE
    assert fields["param1"] == 1  # MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    assert fields["param2"] == number
    assert fields["target_system"] == 7


def test_request_data_streams_asks_for_all_streams() -> None:
    fields = json.loads(ardupilot.request_data_streams_message(3).fields_json)
    assert fields == {
        "target_system": 3,
        "target_component": 1,
        "req_stream_id": 0,
        "req_message_rate": ardupilot.STREAM_RATE_HZ,
        "start_stop": 1,
    }


@pytest.mark.parametrize(
    ("result", "name"),
    [(0, "ACCEPTED"), (2, "DENIED"), (3, "UNSUPPORTED"), (1, "TEMPORARILY_REJECTED"), (9, "RESULT_9")],
)
def test_ack_result_names(result: int, name: str) -> None:
    ack = MavlinkMessage(
        message_name="COMMAND_ACK", fields_json=json.dumps({"command": 176, "result": result})
    )
    assert ardupilot.ack_result(ack) == name


def test_circle_rate_gives_the_tangential_speed() -> None:
    rate = ardupilot.circle_rate_deg_s(5.0, 2.0)
    assert math.radians(rate) * 5.0 == pytest.approx(2.0)
