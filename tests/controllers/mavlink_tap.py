"""A second MAVLink link on the wire between the simulated autopilot and the ground side: an independent reader.

The simulator sends to ``port`` (where MAVSDK would listen); the tap listens there, relays every datagram both
ways (MAVSDK listens on :attr:`MavlinkTap.ground_port`), and decodes what the ground side sends to the autopilot
with its own pymavlink parser: what the autopilot receives, byte for byte, read by a client MAVSDK knows nothing of.
"""

from __future__ import annotations

import os
import socket
import threading
import time

os.environ.setdefault("MAVLINK20", "1")
from pymavlink.dialects.v20 import common as mavlink  # noqa: E402

from controllers.sim.launcher import free_udp_port  # noqa: E402


class MavlinkTap:
    """Relays UDP between the simulator (sending to ``port``) and a ground side on :attr:`ground_port`."""

    def __init__(self, port: int) -> None:
        self.ground_port = free_udp_port()
        self._vehicle_side = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._vehicle_side.bind(("127.0.0.1", port))
        self._ground_side = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._ground_side.bind(("127.0.0.1", 0))
        for sock in (self._vehicle_side, self._ground_side):
            sock.settimeout(0.2)
        self._vehicle_address: tuple[str, int] | None = None
        self._parser = mavlink.MAVLink(None)
        self._parser.robust_parsing = True
        self._lock = threading.Lock()
        self.to_autopilot: list[tuple[int, mavlink.MAVLink_message]] = []
        """(arrival time.monotonic_ns(), message) of everything the ground side sent, oldest first."""
        self._stop = threading.Event()
        self._threads = [threading.Thread(target=self._up, name="tap-up", daemon=True),
                         threading.Thread(target=self._down, name="tap-down", daemon=True)]
        for thread in self._threads:
            thread.start()

    @property
    def connection_string(self) -> str:
        return f"udpin://127.0.0.1:{self.ground_port}"

    def wait_for(self, kind: str, timeout: float = 3.0) -> tuple[int, mavlink.MAVLink_message]:
        """The first ``kind`` message the ground side sent; AssertionError after ``timeout``."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with self._lock:
                found = [(t, m) for t, m in self.to_autopilot if m.get_type() == kind]
            if found:
                return found[0]
            time.sleep(0.02)
        raise AssertionError(f"no {kind} reached the autopilot within {timeout:g} s")

    def close(self) -> None:
        self._stop.set()
        for thread in self._threads:
            thread.join()
        self._vehicle_side.close()
        self._ground_side.close()

    def _up(self) -> None:  # the autopilot's telemetry to the ground side
        while not self._stop.is_set():
            try:
                data, self._vehicle_address = self._vehicle_side.recvfrom(65535)
                self._ground_side.sendto(data, ("127.0.0.1", self.ground_port))
            except (TimeoutError, OSError):
                continue

    def _down(self) -> None:  # the ground side's messages to the autopilot, read on the way
        while not self._stop.is_set():
            try:
                data = self._ground_side.recv(65535)
            except (TimeoutError, OSError):
                continue
            arrived = time.monotonic_ns()
            if self._vehicle_address is not None:
                self._vehicle_side.sendto(data, self._vehicle_address)
            messages = [m for m in self._parser.parse_buffer(data) or [] if m.get_type() != "BAD_DATA"]
            with self._lock:
                self.to_autopilot.extend((arrived, m) for m in messages)
