"""MAVLink connection strings: parse, translate the older forms, check serial devices.

MAVSDK 4 understands ``udpin://HOST:PORT`` (listen), ``udpout://HOST:PORT`` (send to),
``tcpin://HOST:PORT`` (serve), ``tcpout://HOST:PORT`` (connect to a server) and
``serial://DEVICE:BAUD``. The forms older MAVSDK versions (and published papers) used keep their
old meaning here:

============================  ====================================
given                          passed to MAVSDK 4
============================  ====================================
``udp://:14540``               ``udpin://0.0.0.0:14540``
``udp://127.0.0.1:14550``      ``udpin://127.0.0.1:14550``
``tcp://192.168.1.100:5762``   ``tcpout://192.168.1.100:5762``
============================  ====================================

MAVSDK 4 itself would read ``udp://127.0.0.1:14550`` as udpout and then find no autopilot.
"""

from __future__ import annotations

import asyncio
import errno
import logging
import os
from dataclasses import dataclass
from pathlib import Path

from controllers.errors import ConnectError

logger = logging.getLogger(__name__)

EXAMPLES = (
    "serial:///dev/ttyAMA0:57600, serial:///dev/ttyACM0:57600, udpin://0.0.0.0:14540, "
    "udpout://HOST:PORT, tcpout://HOST:PORT, tcpin://0.0.0.0:PORT"
)
"""Shown in every parse error."""

SERIAL_SCHEMES = ("serial", "serial_flowcontrol")
NETWORK_SCHEMES = ("udpin", "udpout", "tcpin", "tcpout")
LEGACY_SCHEMES = {"udp": "udpin", "tcp": "tcpout"}
"""Old MAVSDK scheme -> today's scheme with the same meaning."""

LISTENING_SCHEMES = ("udpin", "tcpin")
DEFAULT_LEGACY_UDP_PORT = 14540
"""Old MAVSDK read a bare ``udp://`` as ``udp://0.0.0.0:14540``."""

SERIAL_DEVICE_GLOBS = ("ttyACM*", "ttyUSB*", "ttyAMA*", "ttyS*")
"""Where flight controllers show up: USB CDC, USB-serial adapters, Pi UARTs, legacy UARTs."""


@dataclass(frozen=True, slots=True)
class Connection:
    """A parsed MAVLink connection string.

    Attributes:
        given: the string as the user wrote it.
        scheme: today's MAVSDK scheme (``udpin``, ``udpout``, ``tcpin``, ``tcpout``, ``serial``, ...).
        host: host or address for network schemes, None for serial.
        port: port for network schemes, None for serial.
        device: device path for serial, None otherwise.
        baud: baud rate for serial, None otherwise.
    """

    given: str
    scheme: str
    host: str | None = None
    port: int | None = None
    device: str | None = None
    baud: int | None = None

    @property
    def url(self) -> str:
        """The string to hand to MAVSDK 4's ``add_any_connection``."""
        if self.is_serial:
            return f"{self.scheme}://{self.device}:{self.baud}"
        return f"{self.scheme}://{self.host}:{self.port}"

    @property
    def is_serial(self) -> bool:
        """True for serial devices (UART on the GPIO header or USB)."""
        return self.scheme in SERIAL_SCHEMES

    @property
    def translated(self) -> bool:
        """True when an older form was rewritten to today's MAVSDK syntax."""
        return self.url != self.given


def parse_connection(address: str) -> Connection:
    """Parse a MAVLink connection string, translating the older forms to MAVSDK 4 syntax.

    Args:
        address: e.g. ``serial:///dev/ttyAMA0:57600``, ``udpin://0.0.0.0:14540``, ``udp://:14540``.

    Returns:
        The parsed connection; ``.url`` is what MAVSDK 4 expects.

    Raises:
        ConnectError: malformed string, unknown scheme, bad port or baud rate.
    """
    text = address.strip()
    scheme, sep, rest = text.partition("://")
    if not sep or not scheme:
        raise ConnectError(f"malformed connection string {address!r}: expected SCHEME://..., e.g. {EXAMPLES}")
    scheme = scheme.lower()
    if scheme in SERIAL_SCHEMES:
        return _parse_serial(address, scheme, rest)
    if scheme in NETWORK_SCHEMES or scheme in LEGACY_SCHEMES:
        return _parse_network(address, scheme, rest)
    raise ConnectError(f"unknown connection scheme {scheme!r} in {address!r}: use one of {EXAMPLES}")


def _parse_serial(address: str, scheme: str, rest: str) -> Connection:
    device, sep, baud_text = rest.rpartition(":")
    if not sep or not device:
        raise ConnectError(
            f"serial connection {address!r} needs a device and a baud rate: {scheme}:///dev/ttyAMA0:57600"
        )
    if not device.startswith("/"):
        raise ConnectError(
            f"serial device in {address!r} must be an absolute path: {scheme}:///dev/ttyAMA0:57600 (three slashes)"
        )
    if not baud_text.isdigit() or int(baud_text) <= 0:
        raise ConnectError(
            f"bad baud rate {baud_text!r} in {address!r}: use the autopilot's SERIALn_BAUD / "
            "SER_TELn_BAUD rate, e.g. 57600 or 921600"
        )
    return Connection(given=address, scheme=scheme, device=device, baud=int(baud_text))


def _parse_network(address: str, scheme: str, rest: str) -> Connection:
    legacy = scheme in LEGACY_SCHEMES
    if "/" in rest or "?" in rest:
        raise ConnectError(f"malformed connection string {address!r}: expected {scheme}://HOST:PORT")
    host, sep, port_text = rest.rpartition(":")
    if not sep:
        if scheme == "udp" and rest == "":
            host, port_text = "", str(DEFAULT_LEGACY_UDP_PORT)
        else:
            raise ConnectError(f"connection {address!r} needs a port: {scheme}://HOST:PORT")
    port = _parse_port(address, port_text)
    new_scheme = LEGACY_SCHEMES.get(scheme, scheme)
    if not host:
        if new_scheme in LISTENING_SCHEMES:
            host = "0.0.0.0"
        elif legacy:
            host = "127.0.0.1"
        else:
            raise ConnectError(f"connection {address!r} needs the host to reach: {scheme}://HOST:{port}")
    if ":" in host or " " in host:
        raise ConnectError(f"malformed host {host!r} in {address!r}: expected {scheme}://HOST:PORT")
    return Connection(given=address, scheme=new_scheme, host=host, port=port)


def _parse_port(address: str, port_text: str) -> int:
    if not port_text.isdigit() or not 1 <= int(port_text) <= 65535:
        raise ConnectError(
            f"bad port {port_text!r} in {address!r}: a number from 1 to 65535 "
            "(PX4 SITL sends to 14540, ground stations listen on 14550)"
        )
    return int(port_text)


def existing_serial_devices(dev_dir: Path = Path("/dev")) -> list[str]:
    """Serial devices a flight controller could be on, sorted: ``/dev/ttyACM0``, ``/dev/ttyAMA0``, ..."""
    return sorted(str(p) for pattern in SERIAL_DEVICE_GLOBS for p in dev_dir.glob(pattern))


def check_serial_device(device: str, *, dev_dir: Path | None = None) -> None:
    """Check that a serial device exists, can be opened and is not held by another process.

    Args:
        device: the device path, e.g. ``/dev/ttyAMA0``.
        dev_dir: where to look for alternatives to list (default: the device's directory).

    Raises:
        ConnectError: missing device (lists those that exist), permission denied, device busy.
    """
    listing_dir = dev_dir if dev_dir is not None else Path(device).parent
    try:
        fd = os.open(device, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    except OSError as exc:
        raise serial_open_error(device, exc, existing_serial_devices(listing_dir)) from exc
    os.close(fd)
    holders = processes_holding(device)
    if holders:
        names = ", ".join(f"{name} (pid {pid})" for pid, name in holders)
        raise ConnectError(
            f"{device} is busy: held open by {names}. Is another MAVLink client (mavproxy, a ground "
            "station, a second uav-tui) using it? Stop it or connect through its forwarded UDP port."
        )


def serial_open_error(device: str, exc: OSError, existing: list[str]) -> ConnectError:
    """Translate the OSError from opening a serial device into a ConnectError saying what to do."""
    if exc.errno == errno.ENOENT:
        found = ", ".join(existing) if existing else "none"
        return ConnectError(
            f"no serial device {device}. Serial devices present: {found}. Check the cable, and on a "
            "Raspberry Pi enable the UART (raspi-config: serial port on, login shell off)."
        )
    if exc.errno in (errno.EACCES, errno.EPERM):
        return ConnectError(
            f"permission denied on {device}: add your user to the dialout group "
            "(sudo usermod -aG dialout $USER), then log out and back in."
        )
    if exc.errno == errno.EBUSY:
        return ConnectError(
            f"{device} is busy: is another MAVLink client (mavproxy, a ground station, ModemManager, "
            "a serial console) using it?"
        )
    return ConnectError(f"cannot open {device}: {exc.strerror or exc}")


def processes_holding(device: str, proc_dir: Path = Path("/proc")) -> list[tuple[int, str]]:
    """Other processes that have ``device`` open, as (pid, command name); best effort."""
    target = os.path.realpath(device)
    me = os.getpid()
    holders: list[tuple[int, str]] = []
    for fd_dir in proc_dir.glob("[0-9]*/fd"):
        pid = int(fd_dir.parent.name)
        if pid == me:
            continue
        try:
            links = [os.readlink(fd) for fd in fd_dir.iterdir()]
            if target in links:
                holders.append((pid, (fd_dir.parent / "comm").read_text().strip()))
        except OSError:
            continue
    return holders


def connection_failed(conn: Connection, reason: str) -> ConnectError:
    """Translate MAVSDK's refusal to open a connection (``"Connection failed: BIND_ERROR"``)."""
    if "BIND_ERROR" in reason:
        return ConnectError(
            f"cannot listen on {conn.url}: the port is in use. Only one process can listen on a UDP "
            "port: is a ground station, mavproxy or another uav-tui running? Pick another port or stop it."
        )
    if conn.is_serial:
        return ConnectError(f"cannot open {conn.device} at {conn.baud} baud ({reason}): check device and baud")
    if "DESTINATION_IP_UNKNOWN" in reason or "CONNECTION_URL_INVALID" in reason:
        return ConnectError(f"cannot resolve host {conn.host!r} in {conn.given!r}: use an IP address")
    if conn.scheme == "tcpout":
        return ConnectError(
            f"nothing accepts TCP connections on {conn.host}:{conn.port} ({reason}): is the autopilot / "
            "SITL running and serving MAVLink on that port?"
        )
    return ConnectError(f"cannot open {conn.url} ({reason})")


async def no_heartbeat_error(conn: Connection, timeout_s: float) -> ConnectError:
    """The error for "nothing answered": says what to check, probing a TCP server once to be precise."""
    if conn.scheme == "tcpout":
        try:
            async with asyncio.timeout(1.0):
                _reader, writer = await asyncio.open_connection(conn.host, conn.port)
            writer.close()
        except (OSError, TimeoutError) as exc:
            return connection_failed(conn, str(exc) or type(exc).__name__)
    hint = " (PX4 SITL sends to udpin://0.0.0.0:14540)" if conn.scheme == "udpin" else ""
    return ConnectError(
        f"no heartbeat on {conn.url} within {timeout_s:g} s: check wiring / baud / port / "
        f"that the autopilot sends to this port{hint}"
    )
