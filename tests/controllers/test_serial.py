"""The serial path (a Pi's UART or USB) end to end through MAVSDK, on a pseudo-terminal."""

from __future__ import annotations

import time

import pytest

from controllers import connect_controller
from controllers.mavsdk.controller import MavsdkController
from tests.controllers.fake_autopilot import FakeAutopilot, PtyLink, mavlink
from uav_tui.errors import ConnectError


async def test_serial_connects_detects_px4_and_commands_reach_the_autopilot() -> None:
    link = PtyLink()
    with FakeAutopilot(link, mavlink.MAV_AUTOPILOT_PX4) as fake:
        fc = await connect_controller(f"serial://{link.device}:57600", heartbeat_timeout=5.0)
        assert isinstance(fc, MavsdkController)
        try:
            assert fc.description == f"PX4 via serial://{link.device}:57600"
            assert fc.heartbeat_age_s() < 1.0
            await fc.arm()
            assert (mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1.0) in [(c, p[0]) for c, p in fake.commands()]
        finally:
            await fc.close()


async def test_silent_serial_port_gives_no_heartbeat_within_bounded_time() -> None:
    link = PtyLink()
    try:
        started = time.monotonic()
        with pytest.raises(ConnectError, match=r"no heartbeat on serial:///dev/pts/\d+:57600 within 1 s: check wiring"):
            await connect_controller(f"serial://{link.device}:57600", heartbeat_timeout=1.0)
        assert time.monotonic() - started < 4.0
    finally:
        link.close()
