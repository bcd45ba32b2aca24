"""A recording stand-in autopilot for protocol tests: heartbeats out, every command ACKed, all recorded.

It speaks MAVLink 2 over UDP (to a ground side listening with ``udpin``) or over a pseudo-terminal
(the ground side opens the pty's device with ``serial://``). It has no physics: tests that use it
check what the controller sends, and the simulated vehicle checks how a vehicle reacts.
"""

from __future__ import annotations

import os
import select
import socket
import threading
import time
from typing import Any

os.environ.setdefault("MAVLINK20", "1")
from pymavlink.dialects.v20 import common as mavlink  # noqa: E402


class UdpLink:
    """Sends to 127.0.0.1:port (the controller's udpin port) from a free local port."""

    def __init__(self, port: int) -> None:
        self._remote = ("127.0.0.1", port)
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.bind(("127.0.0.1", 0))
        self._sock.settimeout(0.05)

    def write(self, data: bytes) -> None:
        self._sock.sendto(data, self._remote)

    def read(self) -> bytes:
        try:
            return self._sock.recvfrom(65535)[0]
        except OSError:
            return b""

    def close(self) -> None:
        self._sock.close()


class PtyLink:
    """A pseudo-terminal: the controller opens ``device`` as a serial port, we hold the other end."""

    def __init__(self) -> None:
        self._master, self._slave = os.openpty()
        self.device = os.ttyname(self._slave)

    def write(self, data: bytes) -> None:
        os.write(self._master, data)

    def read(self) -> bytes:
        ready, _, _ = select.select([self._master], [], [], 0.05)
        return os.read(self._master, 4096) if ready else b""

    def close(self) -> None:
        os.close(self._master)
        os.close(self._slave)


class FakeAutopilot:
    """Heartbeats as ``autopilot`` (MAV_AUTOPILOT_*) every 0.2 s; ACKs commands and parameters.

    DO_ORBIT is answered UNSUPPORTED when ``orbit_supported`` is False (ArduCopter does that).
    """

    def __init__(self, link: UdpLink | PtyLink, autopilot: int, *, orbit_supported: bool = True) -> None:
        self.link = link
        self.autopilot = autopilot
        self.orbit_supported = orbit_supported
        self.tx = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        self.rx = mavlink.MAVLink(None)
        self.rx.robust_parsing = True
        self.received: list[Any] = []
        self._arrived: list[tuple[float, Any]] = []
        """(time.monotonic() at arrival, message) of each of ``received``."""
        self.mode, self.armed = 0, False
        self.params: dict[str, float] = {}
        """Parameters it serves (PARAM_REQUEST_READ) and stores (PARAM_SET): REAL32, INT32 for an ``int`` (in
        ArduPilot's C-cast encoding, the value as a float)."""
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="fake-autopilot", daemon=True)

    def __enter__(self) -> FakeAutopilot:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()
        self.link.close()

    def commands(self) -> list[tuple[int, list[float]]]:
        """(command, [param1..param7]) of every COMMAND_LONG received, oldest first."""
        return [
            (m.command, [m.param1, m.param2, m.param3, m.param4, m.param5, m.param6, m.param7])
            for m in list(self.received)
            if m.get_type() == "COMMAND_LONG"
        ]

    def of_type(self, name: str) -> list[Any]:
        return [m for m in list(self.received) if m.get_type() == name]

    def arrivals(self, name: str) -> list[tuple[float, Any]]:
        """(arrival time, message) of every ``name`` received, oldest first."""
        return [(t, m) for t, m in list(self._arrived) if m.get_type() == name]

    def _send(self, msg: Any) -> None:
        self.link.write(msg.pack(self.tx))

    def _heartbeat(self) -> None:
        base = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (mavlink.MAV_MODE_FLAG_SAFETY_ARMED if self.armed else 0)
        self._send(self.tx.heartbeat_encode(mavlink.MAV_TYPE_QUADROTOR, self.autopilot, base, self.mode, 4))

    def _run(self) -> None:
        last = 0.0
        while not self._stop.is_set():
            if time.monotonic() - last > 0.2:
                self._heartbeat()
                last = time.monotonic()
            for msg in self.rx.parse_buffer(self.link.read()) or []:
                self._arrived.append((time.monotonic(), msg))
                self.received.append(msg)
                self._answer(msg)

    def _answer(self, msg: Any) -> None:
        kind = msg.get_type()
        if kind in ("COMMAND_LONG", "COMMAND_INT"):
            result = mavlink.MAV_RESULT_ACCEPTED
            if msg.command == mavlink.MAV_CMD_DO_SET_MODE:
                self.mode = int(msg.param2)
            elif msg.command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM:
                self.armed = msg.param1 > 0.5
            elif msg.command == mavlink.MAV_CMD_DO_ORBIT and not self.orbit_supported:
                result = mavlink.MAV_RESULT_UNSUPPORTED
            self._send(
                self.tx.command_ack_encode(msg.command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent())
            )
            if msg.command == mavlink.MAV_CMD_DO_SET_MODE:
                self._heartbeat()
        elif kind == "PARAM_SET":
            name = msg.param_id if isinstance(msg.param_id, str) else msg.param_id.decode()
            if name in self.params:
                self.params[name] = int(msg.param_value) if isinstance(self.params[name], int) else msg.param_value
            self._send(self.tx.param_value_encode(name.encode(), msg.param_value, msg.param_type, 1, 0))
        elif kind == "PARAM_REQUEST_READ":
            name = msg.param_id if isinstance(msg.param_id, str) else msg.param_id.decode()
            if name in self.params:  # unknown: silent, as autopilots are
                value = self.params[name]
                kind = mavlink.MAV_PARAM_TYPE_INT32 if isinstance(value, int) else mavlink.MAV_PARAM_TYPE_REAL32
                self._send(self.tx.param_value_encode(name.encode(), value, kind, len(self.params), 0))
