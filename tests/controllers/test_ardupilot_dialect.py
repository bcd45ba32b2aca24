"""The controller speaks ArduCopter's dialect (through real MAVSDK) to a recording stand-in.

No ArduPilot SITL runs here, so a small pymavlink responder plays the autopilot: it sends ArduCopter
heartbeats, accepts every command and parameter, and records what arrives. These tests check what
the controller sends (streams requested, GUIDED before arming, NAV_TAKEOFF altitude, CIRCLE for
orbits, LOITER for hold), not how ArduCopter reacts to it.
"""

from __future__ import annotations

import asyncio
import os
import socket
import threading
import time
from collections.abc import AsyncIterator
from typing import Any

import pytest
import pytest_asyncio

os.environ.setdefault("MAVLINK20", "1")
from pymavlink.dialects.v20 import common as mavlink  # noqa: E402

from controllers.mavsdk_controller import MavsdkController  # noqa: E402

GUIDED, LOITER, CIRCLE = 4, 5, 7


class FakeArduCopter:
    """Sends ArduCopter heartbeats to a listening port; ACKs and records what comes back."""

    def __init__(self, port: int) -> None:
        self.remote = ("127.0.0.1", port)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.05)
        self.tx = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        self.rx = mavlink.MAVLink(None)
        self.rx.robust_parsing = True
        self.received: list[Any] = []
        self.mode, self.armed = 0, False
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="fake-arducopter", daemon=True)

    def __enter__(self) -> FakeArduCopter:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()
        self.sock.close()

    def commands(self) -> list[tuple[int, list[float]]]:
        return [
            (m.command, [m.param1, m.param2, m.param3, m.param4, m.param5, m.param6, m.param7])
            for m in list(self.received)
            if m.get_type() == "COMMAND_LONG"
        ]

    def of_type(self, name: str) -> list[Any]:
        return [m for m in list(self.received) if m.get_type() == name]

    def _send(self, msg: Any, addr: Any = None) -> None:
        self.sock.sendto(msg.pack(self.tx), addr or self.remote)

    def _heartbeat(self) -> None:
        base = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (mavlink.MAV_MODE_FLAG_SAFETY_ARMED if self.armed else 0)
        self._send(
            self.tx.heartbeat_encode(
                mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, base, self.mode, 4
            )
        )

    def _run(self) -> None:
        last = 0.0
        while not self._stop.is_set():
            if time.monotonic() - last > 0.2:
                self._heartbeat()
                last = time.monotonic()
            try:
                data, addr = self.sock.recvfrom(65535)
            except OSError:
                continue
            for msg in self.rx.parse_buffer(data) or []:
                self.received.append(msg)
                self._answer(msg, addr)

    def _answer(self, msg: Any, addr: Any) -> None:
        kind = msg.get_type()
        if kind in ("COMMAND_LONG", "COMMAND_INT"):
            result = mavlink.MAV_RESULT_ACCEPTED
            if msg.command == mavlink.MAV_CMD_DO_SET_MODE:
                self.mode = int(msg.param2)
            elif msg.command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM:
                self.armed = msg.param1 > 0.5
            elif msg.command == mavlink.MAV_CMD_DO_ORBIT:
                result = mavlink.MAV_RESULT_UNSUPPORTED
            ack = self.tx.command_ack_encode(msg.command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent())
            self._send(ack, addr)
            if msg.command == mavlink.MAV_CMD_DO_SET_MODE:
                self._heartbeat()
        elif kind == "PARAM_SET":
            name = msg.param_id if isinstance(msg.param_id, str) else msg.param_id.decode()
            self._send(self.tx.param_value_encode(name.encode(), msg.param_value, msg.param_type, 1, 0), addr)


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest_asyncio.fixture
async def copter() -> AsyncIterator[tuple[MavsdkController, FakeArduCopter]]:
    port = free_udp_port()
    with FakeArduCopter(port) as fake:
        fc = MavsdkController()
        await fc.connect(f"udpin://127.0.0.1:{port}", heartbeat_timeout=5.0)
        try:
            yield fc, fake
        finally:
            await fc.close()


def set_modes(fake: FakeArduCopter) -> list[int]:
    return [int(p[1]) for c, p in fake.commands() if c == mavlink.MAV_CMD_DO_SET_MODE]


async def test_detected_and_asked_for_its_streams(copter: tuple[MavsdkController, FakeArduCopter]) -> None:
    fc, fake = copter
    assert fc.autopilot == "ardupilot"
    assert fc.description.startswith("ArduPilot via udpin://")
    (request,) = fake.of_type("REQUEST_DATA_STREAM")
    assert (request.req_stream_id, request.start_stop, request.req_message_rate) == (0, 1, 10)


async def test_guided_before_arming_and_takeoff_altitude(copter: tuple[MavsdkController, FakeArduCopter]) -> None:
    fc, fake = copter
    await fc.arm()
    await fc.takeoff(4.0)
    sequence = [(c, p[1] if c == mavlink.MAV_CMD_DO_SET_MODE else p[0]) for c, p in fake.commands()]
    flight = {mavlink.MAV_CMD_DO_SET_MODE, mavlink.MAV_CMD_COMPONENT_ARM_DISARM}
    sequence = [s for s in sequence if s[0] in flight]
    assert sequence[:2] == [(mavlink.MAV_CMD_DO_SET_MODE, GUIDED), (mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1.0)]
    (takeoff,) = [p for c, p in fake.commands() if c == mavlink.MAV_CMD_NAV_TAKEOFF]
    assert takeoff[6] == 4.0


async def test_vector_in_guided_then_loiter(copter: tuple[MavsdkController, FakeArduCopter]) -> None:
    fc, fake = copter
    await fc.set_fly_vector(0.5, 0.25, 0.5)
    while fc.vector_active:
        await asyncio.sleep(0.05)
    assert set_modes(fake)[-2:] == [GUIDED, LOITER]
    setpoints = fake.of_type("SET_POSITION_TARGET_LOCAL_NED")
    moving = [s for s in setpoints if (s.vx, s.vy) == (0.5, 0.25)]
    assert len(moving) >= 8  # 0.5 s at 20 Hz, well within GUID_TIMEOUT
    assert all(s.coordinate_frame == mavlink.MAV_FRAME_BODY_NED for s in setpoints)
    assert (setpoints[-1].vx, setpoints[-1].vy) == (0.0, 0.0)
    assert fc.last_vector_end == "completed"


async def test_orbit_is_circle_mode_and_hold_is_loiter(copter: tuple[MavsdkController, FakeArduCopter]) -> None:
    fc, fake = copter
    await fc.do_orbit(5.0, 2.0)
    params = {
        (m.param_id if isinstance(m.param_id, str) else m.param_id.decode()): m.param_value
        for m in fake.of_type("PARAM_SET")
    }
    assert params["CIRCLE_RADIUS_M"] == 5.0
    assert params["CIRCLE_RATE"] == pytest.approx(22.918, abs=0.01)  # 2 m/s on 5 m
    assert set_modes(fake)[-1] == CIRCLE
    assert not [c for c, _ in fake.commands() if c == mavlink.MAV_CMD_DO_ORBIT]
    await fc.hold()
    assert set_modes(fake)[-1] == LOITER
