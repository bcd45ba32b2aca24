"""Hostile datagrams to the MAVLink camera component of a real ``uav-tui --no-ui``, from an independent
pymavlink ground station on a link of its own: a bad field is refused with an ACK and the component keeps
answering; a flood is dropped, counted and said in a bounded number of lines."""

from __future__ import annotations

import asyncio
import os
import re
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import common as mavlink

from tests.web.conftest import free_port, interrupt
from tests.web.test_camera_tracking import GroundStation

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def platform(tmp_path: Path) -> Iterator[tuple[int, Path]]:
    """``uav-tui --no-ui`` with the camera component on a UDP port; yields (port, its output file)."""
    port = free_port(socket.SOCK_DGRAM)
    output = tmp_path / "output.txt"
    with open(output, "w") as sink:
        process = subprocess.Popen(
            [sys.executable, "-m", "uav_tui", "--no-ui", "--fc", "none", "--source", "synthetic:", "--no-record",
             "--processor", "tests.web.conftest:RecordingProcessor", "--camera-mavlink", f"udpin:127.0.0.1:{port}",
             "--duration", "90"],
            cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)}, stdout=sink, stderr=subprocess.STDOUT)
    try:
        yield port, output
    finally:
        interrupt(process)


async def answered(station: GroundStation, param1: float, timeout: float = 3.0) -> int | None:
    """Send MAV_CMD_REQUEST_MESSAGE(param1); the ACK's result, or None when none comes."""
    await station.command(mavlink.MAV_CMD_REQUEST_MESSAGE, param1)
    try:
        ack = await station.receive("COMMAND_ACK", timeout=timeout, command=mavlink.MAV_CMD_REQUEST_MESSAGE)
    except TimeoutError:
        return None
    return int(ack.result)


async def connected(port: int) -> GroundStation:
    """A ground station once the component answers (the platform takes a few seconds to start)."""
    station = GroundStation(port)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        if await answered(station, mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION, timeout=0.5) is not None:
            return station
    station.sock.close()
    pytest.fail("the camera component never answered")


@pytest.mark.timeout(180)
async def test_a_bad_field_is_refused_and_later_commands_are_still_answered(platform: tuple[int, Path]) -> None:
    port, output = platform
    station = await connected(port)
    try:
        for bad in (float("nan"), float("inf"), -float("inf"), 1e30, -3.0, 33.5):
            assert await answered(station, bad) == mavlink.MAV_RESULT_DENIED, f"param1 = {bad}"
        assert await answered(station, mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION) == mavlink.MAV_RESULT_ACCEPTED
        info = await station.receive("CAMERA_INFORMATION")
        assert info.flags & mavlink.CAMERA_CAP_FLAGS_HAS_TRACKING_RECTANGLE
    finally:
        station.sock.close()
    await asyncio.sleep(0.5)
    assert "param1 = nan is not a MAVLink message id" in output.read_text()  # said to the operator


@pytest.mark.timeout(180)
async def test_a_flood_is_counted_in_a_bounded_number_of_lines(platform: tuple[int, Path]) -> None:
    port, output = platform
    station = await connected(port)
    try:
        packet = station.mav.command_long_encode(1, 100, mavlink.MAV_CMD_CAMERA_TRACK_POINT, 0, 0.5, 0.5, 0.05,
                                                 0, 0, 0, 0).pack(station.mav)  # each one calls the processor
        flood = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:  # 30,000 in bursts a receive buffer holds (the kernel drops the rest of a burst unread)
            for _ in range(300):
                for _ in range(100):
                    flood.sendto(packet, station.address)
                await asyncio.sleep(0.002)
        finally:
            flood.close()
        await asyncio.sleep(2.5)  # the count is said within a second of the last drop
        assert await answered(station, mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION) == mavlink.MAV_RESULT_ACCEPTED
    finally:
        station.sock.close()
    printed = output.read_text().splitlines()
    lines = [line for line in printed if "camera component: drop" in line]
    assert 2 <= len(lines) <= 12 and "is something flooding" in lines[0], lines[:20]
    # A pause of a second in the flood (a loaded machine) says the first drop again: each such line stands for one.
    said = sum("is something flooding" in line for line in lines)
    counts = [re.search(r"dropped (\d+) more commands? \((\d+) in all\)", line) for line in lines]
    counted = [count for count in counts if count is not None]
    assert said + len(counted) == len(lines) and counted, lines
    dropped = said + sum(int(count[1]) for count in counted)
    assert int(counted[-1][2]) == dropped, lines  # each count says how many it stands for
    assert dropped > 300, lines  # how many arrive is the kernel's call under load: 887 to 29,000 seen
    assert len(printed) < 150  # the commands taken (a few a second) and their outcomes included
