"""The simulator's MAVLink 2 endpoint: one UDP socket that sends to the ground side's listening port
(like PX4 SITL's ``udpout``) and reads whatever the ground side sends back to it."""

from __future__ import annotations

import logging
import os
import socket
import struct
import sys
import threading
import time

os.environ.setdefault("MAVLINK20", "1")

import contextlib

from pymavlink.dialects.v20 import common as mavlink  # noqa: E402

logger = logging.getLogger(__name__)

SYSTEM_ID = 1
COMPONENT_ID = mavlink.MAV_COMP_ID_AUTOPILOT1
_SO_TIMESTAMPNS = 35
"""Linux: the kernel stamps each datagram with CLOCK_REALTIME when it arrives (not in Python's socket)."""
_TIMESPEC = struct.Struct("@ll")


def arrival_mono_ns(ancdata: list[tuple[int, int, bytes]]) -> int:
    """When the datagram reached the socket, on the time.monotonic_ns() clock.

    Uses the kernel's receive timestamp when there is one, so a busy interpreter does not delay the
    stamp; otherwise the time of reading.
    """
    now_mono = time.monotonic_ns()
    for level, kind, payload in ancdata:
        if level == socket.SOL_SOCKET and kind == _SO_TIMESTAMPNS and len(payload) >= _TIMESPEC.size:
            sec, nsec = _TIMESPEC.unpack_from(payload)
            wall_to_mono = time.time_ns() - time.monotonic_ns()
            return min(now_mono, sec * 1_000_000_000 + nsec - wall_to_mono)
    return now_mono


class MavlinkLink:
    """Encodes and sends messages as system 1 / autopilot component; decodes received datagrams.

    ``send`` is thread-safe; ``receive`` is meant for one reader thread.
    """

    def __init__(self, remote_port: int, host: str = "127.0.0.1") -> None:
        self.remote = (host, remote_port)
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.bind((host, 0))
        self._sock.settimeout(0.2)
        if sys.platform.startswith("linux"):
            try:
                self._sock.setsockopt(socket.SOL_SOCKET, _SO_TIMESTAMPNS, 1)
            except OSError as exc:  # e.g. ENOPROTOOPT under an emulator: stamp datagrams when read instead
                logger.info("no kernel receive timestamps (%s); arrival time is the time of reading", exc)
        self._tx = mavlink.MAVLink(None, srcSystem=SYSTEM_ID, srcComponent=COMPONENT_ID)
        self._rx = mavlink.MAVLink(None)
        self._rx.robust_parsing = True
        self._lock = threading.Lock()
        self.sent = 0
        self.received = 0

    @property
    def encoder(self) -> mavlink.MAVLink:
        """Use its ``*_encode`` methods to build messages (they do not send)."""
        return self._tx

    def send(self, msg: mavlink.MAVLink_message) -> None:
        with self._lock:
            buf = msg.pack(self._tx)
            try:
                self._sock.sendto(buf, self.remote)
            except OSError as exc:
                logger.debug("MavlinkLink(%s) send failed: %s", self.remote, exc)
                return
            self.sent += 1

    def receive(self) -> tuple[list[mavlink.MAVLink_message], int]:
        """Block up to 0.2 s for one datagram: (decoded messages, arrival time.monotonic_ns())."""
        try:
            data, ancdata, _flags, _addr = self._sock.recvmsg(65535, 256)
        except (TimeoutError, OSError):
            return [], 0
        t_ns = arrival_mono_ns(ancdata)
        msgs = self._rx.parse_buffer(data) or []
        good = [m for m in msgs if m.get_type() != "BAD_DATA"]
        self.received += len(good)
        return good, t_ns

    def wake(self) -> None:
        """Unblock a reader waiting in :meth:`receive` (an empty datagram to ourselves)."""
        with contextlib.suppress(OSError):
            self._sock.sendto(b"", self._sock.getsockname())

    def close(self) -> None:
        self._sock.close()
