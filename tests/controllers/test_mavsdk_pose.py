"""The pose stream for the sim: camera: rate request, message parsing, autopilot clock mapping, and the real stream."""

from __future__ import annotations

import json
import math
import time

import pytest
from mavsdk.asyncio.plugins.mavlink_direct import MavlinkMessage

from controllers.mavsdk.controller import MavsdkController
from controllers.mavsdk.pose import (
    CLOCK_WINDOW_S,
    BootClock,
    message_interval_command,
    parse_pose_message,
)
from controllers.sim.launcher import SimVehicle

MS = 1_000_000


def test_rate_request_is_set_message_interval_in_microseconds() -> None:
    fields = json.loads(message_interval_command(1, 32, 50.0).fields_json)
    assert (fields["command"], fields["param1"], fields["param2"]) == (511, 32.0, 20_000.0)


def test_messages_are_parsed_into_metres_and_degrees() -> None:
    position = MavlinkMessage(message_name="LOCAL_POSITION_NED", system_id=1,
                              fields_json=json.dumps({"time_boot_ms": 1500, "x": 1.5, "y": -2.0, "z": -10.0}))
    attitude = MavlinkMessage(message_name="ATTITUDE", system_id=1,
                              fields_json=json.dumps({"time_boot_ms": 1510, "roll": 0.1, "pitch": -0.2,
                                                      "yaw": math.pi / 2}))
    assert parse_pose_message(position) == ("position", 1500, (1.5, -2.0, -10.0))
    kind, boot_ms, angles = parse_pose_message(attitude)
    assert (kind, boot_ms) == ("attitude", 1510) and angles == pytest.approx((5.7296, -11.4592, 90.0), abs=1e-3)
    assert parse_pose_message(MavlinkMessage(message_name="ATTITUDE", fields_json="{}")) is None


def test_clock_takes_the_fastest_delivery_and_restarts_with_the_autopilot() -> None:
    clock = BootClock()
    start = 1_000_000 * MS
    # Sent at boot 0, 20, 40 ms; delivered 9, 2 and 6 ms later: the 2 ms delivery bounds the offset.
    mapped = [clock.to_mono_ns(boot, start + boot * MS + delay * MS) for boot, delay in ((0, 9), (20, 2), (40, 6))]
    assert mapped[-1] == start + 42 * MS and mapped[1] == start + 22 * MS
    later = start + int(2 * CLOCK_WINDOW_S * 1e9)  # the 2 ms sample has left the window
    assert clock.to_mono_ns(int(2 * CLOCK_WINDOW_S * 1000), later + 5 * MS) == later + 5 * MS
    rebooted = later + 30_000 * MS
    assert clock.to_mono_ns(100, rebooted + 3 * MS) == rebooted + 3 * MS  # boot time back at 0.1 s


def test_clock_maps_our_time_onto_the_autopilots_boot_clock() -> None:
    clock = BootClock()
    assert clock.boot_us(5 * MS) is None  # nothing heard from the autopilot yet
    start = 1_000_000 * MS
    for boot, delay in ((0, 9), (20, 2), (40, 6)):
        clock.observe(boot, start + boot * MS + delay * MS)
    assert clock.boot_us(start + 100 * MS) == 98_000  # the fastest delivery (2 ms) bounds the offset


async def test_the_autopilot_streams_the_pose_at_50_hz_stamped_when_it_was_true(sim_vehicle: SimVehicle) -> None:
    fc = MavsdkController()
    await fc.connect(sim_vehicle.connection_string)
    truth = sim_vehicle.truth()
    try:
        samples, first = [], None
        async for sample in fc.pose_samples():
            first = first or time.monotonic()
            samples.append((sample, truth.latest()))
            if time.monotonic() - first > 2.0:
                break
    finally:
        await fc.close()
    positions = [s for s, _ in samples if s.kind == "position"]
    attitudes = [s for s, _ in samples if s.kind == "attitude"]
    assert len(positions) > 80 and len(attitudes) > 80  # 50 Hz each asked, default is 25 Hz for positions
    assert all(b.t_mono_ns >= a.t_mono_ns for a, b in zip(positions, positions[1:], strict=False))
    # Stamped on our clock, never in the future.
    assert all(s.t_mono_ns <= time.monotonic_ns() for s in positions)
    parked = samples[-1][1]
    assert positions[-1].values == pytest.approx((parked["n"], parked["e"], parked["d"]), abs=1e-3)
    assert attitudes[-1].values[2] == pytest.approx(parked["yaw"], abs=1e-2)
