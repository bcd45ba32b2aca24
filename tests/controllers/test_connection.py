"""Connection strings: parsing, translation of the older forms, serial device checks."""

from __future__ import annotations

import errno
import os
import subprocess
from pathlib import Path

import pytest

from controllers.connection import (
    Connection,
    check_serial_device,
    connection_failed,
    existing_serial_devices,
    parse_connection,
    serial_open_error,
)
from uav_tui.errors import ConnectError


@pytest.mark.parametrize(
    ("given", "url"),
    [
        pytest.param("serial:///dev/ttyAMA0:57600", "serial:///dev/ttyAMA0:57600", id="serial-uart"),
        pytest.param("serial:///dev/ttyACM0:57600", "serial:///dev/ttyACM0:57600", id="serial-usb"),
        pytest.param(
            "serial_flowcontrol:///dev/ttyUSB0:921600", "serial_flowcontrol:///dev/ttyUSB0:921600", id="flow"
        ),
        pytest.param("udpin://0.0.0.0:14540", "udpin://0.0.0.0:14540", id="udpin"),
        pytest.param("udpin://:14540", "udpin://0.0.0.0:14540", id="udpin-empty-host"),
        pytest.param("udpout://10.0.0.5:14550", "udpout://10.0.0.5:14550", id="udpout"),
        pytest.param("tcpout://192.168.1.100:5762", "tcpout://192.168.1.100:5762", id="tcpout"),
        pytest.param("tcpin://0.0.0.0:5760", "tcpin://0.0.0.0:5760", id="tcpin"),
        pytest.param("tcpin://:5760", "tcpin://0.0.0.0:5760", id="tcpin-empty-host"),
        pytest.param("UDPIN://0.0.0.0:14540", "udpin://0.0.0.0:14540", id="scheme-case"),
        pytest.param("  udpin://0.0.0.0:14540 ", "udpin://0.0.0.0:14540", id="whitespace"),
        pytest.param("udpout://sitl.local:14550", "udpout://sitl.local:14550", id="hostname"),
    ],
)
def test_current_forms_pass_through(given: str, url: str) -> None:
    assert parse_connection(given).url == url


@pytest.mark.parametrize(
    ("given", "url"),
    [
        pytest.param("udp://:14540", "udpin://0.0.0.0:14540", id="udp-empty-host-listens"),
        pytest.param("udp://127.0.0.1:14550", "udpin://127.0.0.1:14550", id="udp-host-listens"),
        pytest.param("udp://", "udpin://0.0.0.0:14540", id="udp-bare-default-port"),
        pytest.param("tcp://192.168.1.100:5762", "tcpout://192.168.1.100:5762", id="tcp-connects"),
        pytest.param("tcp://:5760", "tcpout://127.0.0.1:5760", id="tcp-empty-host-local"),
    ],
)
def test_old_forms_keep_their_old_meaning(given: str, url: str) -> None:
    conn = parse_connection(given)
    assert conn.url == url
    assert conn.translated


def test_serial_fields() -> None:
    conn = parse_connection("serial:///dev/ttyAMA0:57600")
    assert conn == Connection(
        given="serial:///dev/ttyAMA0:57600", scheme="serial", device="/dev/ttyAMA0", baud=57600
    )
    assert conn.is_serial
    assert not conn.translated


@pytest.mark.parametrize(
    ("given", "says"),
    [
        pytest.param("", "expected SCHEME://", id="empty"),
        pytest.param("/dev/ttyAMA0", "expected SCHEME://", id="no-scheme"),
        pytest.param("127.0.0.1:14540", "expected SCHEME://", id="host-port-only"),
        pytest.param("://0.0.0.0:14540", "expected SCHEME://", id="empty-scheme"),
        pytest.param("http://0.0.0.0:14540", "unknown connection scheme 'http'", id="unknown-scheme"),
        pytest.param("udpin://0.0.0.0:99999", "bad port '99999'", id="port-too-big"),
        pytest.param("udpin://0.0.0.0:0", "bad port '0'", id="port-zero"),
        pytest.param("udpin://0.0.0.0:abc", "bad port 'abc'", id="port-not-number"),
        pytest.param("udpin://0.0.0.0:", "bad port ''", id="port-empty"),
        pytest.param("udpin://0.0.0.0", "needs a port", id="port-missing"),
        pytest.param("udpout://:14550", "needs the host", id="udpout-no-host"),
        pytest.param("tcpout://:5760", "needs the host", id="tcpout-no-host"),
        pytest.param("udpin://0.0.0.0:14540/x", "expected udpin://HOST:PORT", id="path"),
        pytest.param("serial:///dev/ttyAMA0", "needs a device and a baud rate", id="serial-no-baud"),
        pytest.param("serial:///dev/ttyAMA0:fast", "bad baud rate 'fast'", id="serial-bad-baud"),
        pytest.param("serial://dev/ttyAMA0:57600", "absolute path", id="serial-two-slashes"),
        pytest.param("serial://:57600", "needs a device", id="serial-no-device"),
    ],
)
def test_malformed_strings_say_what_to_do(given: str, says: str) -> None:
    with pytest.raises(ConnectError) as info:
        parse_connection(given)
    assert says in str(info.value)


def test_missing_device_lists_the_ones_that_exist(tmp_path: Path) -> None:
    for name in ("ttyACM0", "ttyAMA0", "ttyS0", "video0"):
        (tmp_path / name).touch()
    with pytest.raises(ConnectError) as info:
        check_serial_device(str(tmp_path / "ttyUSB0"))
    message = str(info.value)
    assert f"no serial device {tmp_path / 'ttyUSB0'}" in message
    assert f"{tmp_path / 'ttyACM0'}, {tmp_path / 'ttyAMA0'}, {tmp_path / 'ttyS0'}" in message
    assert "video0" not in message


def test_missing_device_with_none_present(tmp_path: Path) -> None:
    with pytest.raises(ConnectError, match="Serial devices present: none"):
        check_serial_device(str(tmp_path / "ttyAMA0"))


def test_existing_serial_devices_sorted(tmp_path: Path) -> None:
    for name in ("ttyUSB1", "ttyACM0", "ttyUSB0", "ttyprintk"):
        (tmp_path / name).touch()
    assert existing_serial_devices(tmp_path) == [str(tmp_path / n) for n in ("ttyACM0", "ttyUSB0", "ttyUSB1")]


@pytest.mark.parametrize(
    ("err", "says"),
    [
        pytest.param(errno.EACCES, "add your user to the dialout group", id="eacces"),
        pytest.param(errno.EPERM, "add your user to the dialout group", id="eperm"),
        pytest.param(errno.EBUSY, "is busy", id="ebusy"),
        pytest.param(errno.EIO, "cannot open /dev/ttyAMA0", id="other"),
    ],
)
def test_open_errors_say_what_to_do(err: int, says: str) -> None:
    # Root (the test machine) is never refused a device, so the OSError is built here.
    error = serial_open_error("/dev/ttyAMA0", OSError(err, os.strerror(err)), [])
    assert isinstance(error, ConnectError)
    assert says in str(error)


def test_free_tty_passes() -> None:
    master, slave = os.openpty()
    try:
        check_serial_device(os.ttyname(slave))
    finally:
        os.close(master)
        os.close(slave)


def test_tty_held_by_another_process_is_busy() -> None:
    master, slave = os.openpty()
    holder = subprocess.Popen(["sleep", "30"], stdin=slave)
    try:
        with pytest.raises(ConnectError, match=r"is busy: held open by sleep \(pid \d+\)"):
            check_serial_device(os.ttyname(slave))
    finally:
        holder.kill()
        holder.wait()
        os.close(master)
        os.close(slave)


@pytest.mark.parametrize(
    ("given", "reason", "says"),
    [
        pytest.param(
            "udpin://0.0.0.0:14540", "Connection failed: BIND_ERROR", "the port is in use", id="bind"
        ),
        pytest.param(
            "tcpout://127.0.0.1:5760", "Connection failed: CONNECTION_ERROR", "nothing accepts", id="tcp"
        ),
        pytest.param(
            "serial:///dev/ttyS0:57600", "Connection failed: CONNECTION_ERROR", "check device", id="serial"
        ),
        pytest.param(
            "udpout://nohost:1", "Connection failed: DESTINATION_IP_UNKNOWN", "cannot resolve", id="dns"
        ),
    ],
)
def test_mavsdk_refusals_say_what_to_do(given: str, reason: str, says: str) -> None:
    assert says in str(connection_failed(parse_connection(given), reason))
