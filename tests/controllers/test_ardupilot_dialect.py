"""The controller speaks ArduCopter's dialect (through real MAVSDK) to a recording stand-in.

No ArduPilot SITL runs here, so :class:`FakeAutopilot` plays an ArduCopter: these tests check what
the controller sends (streams requested, GUIDED before arming, NAV_TAKEOFF altitude, CIRCLE for
orbits, GUIDED at zero velocity for hold, never LOITER), not how ArduCopter reacts to it (the
simulator's ``ardupilot`` dialect and ``test_ardupilot_hold.py`` check that).
"""

from __future__ import annotations

import asyncio
import itertools
from collections.abc import AsyncIterator

import pytest
import pytest_asyncio

from controllers.autopilots import Autopilot
from controllers.mavsdk import ardupilot
from controllers.mavsdk.controller import MavsdkController
from controllers.sim.launcher import free_udp_port
from controllers.vector_end import VectorEnd, VectorEndKind
from tests.controllers.fake_autopilot import FakeAutopilot, UdpLink, mavlink

GUIDED, CIRCLE = 4, 7


@pytest_asyncio.fixture
async def copter() -> AsyncIterator[tuple[MavsdkController, FakeAutopilot]]:
    port = free_udp_port()
    link = UdpLink(port)
    with FakeAutopilot(link, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, orbit_supported=False) as fake:
        fc = MavsdkController()
        await fc.connect(f"udpin://127.0.0.1:{port}", heartbeat_timeout=5.0)
        try:
            yield fc, fake
        finally:
            await fc.close()


def set_modes(fake: FakeAutopilot) -> list[int]:
    return [int(p[1]) for c, p in fake.commands() if c == mavlink.MAV_CMD_DO_SET_MODE]


async def test_detected_and_asked_for_its_streams(copter: tuple[MavsdkController, FakeAutopilot]) -> None:
    fc, fake = copter
    assert fc.autopilot is Autopilot.ARDUPILOT
    assert fc.description.startswith("ArduPilot via udpin://")
    (request,) = fake.of_type("REQUEST_DATA_STREAM")
    assert (request.req_stream_id, request.start_stop, request.req_message_rate) == (0, 1, 10)


async def test_guided_before_arming_and_takeoff_altitude(copter: tuple[MavsdkController, FakeAutopilot]) -> None:
    fc, fake = copter
    await fc.arm()
    await fc.takeoff(4.0)
    sequence = [(c, p[1] if c == mavlink.MAV_CMD_DO_SET_MODE else p[0]) for c, p in fake.commands()]
    flight = {mavlink.MAV_CMD_DO_SET_MODE, mavlink.MAV_CMD_COMPONENT_ARM_DISARM}
    sequence = [s for s in sequence if s[0] in flight]
    assert sequence[:2] == [(mavlink.MAV_CMD_DO_SET_MODE, GUIDED), (mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1.0)]
    (takeoff,) = [p for c, p in fake.commands() if c == mavlink.MAV_CMD_NAV_TAKEOFF]
    assert takeoff[6] == 4.0


async def test_vector_in_guided_then_held_in_guided(copter: tuple[MavsdkController, FakeAutopilot]) -> None:
    fc, fake = copter
    fake.mode = GUIDED  # as after a take-off (a vector from a pilot's mode is refused)
    async with asyncio.timeout(10):
        while fc.flight_mode_since(0.0) != "OFFBOARD":  # MAVSDK's name of GUIDED
            await asyncio.sleep(0.05)
    await fc.set_fly_vector(0.5, 0.25, 1.0)
    async with asyncio.timeout(10):  # a 1 s vector; a stream that never ends fails here, not at the suite timeout
        while fc.vector_active:
            await asyncio.sleep(0.05)
    assert set_modes(fake)[-2:] == [GUIDED, GUIDED]  # LOITER would fly the RC throttle stick
    setpoints = fake.of_type("SET_POSITION_TARGET_LOCAL_NED")
    moving = [t for t, s in fake.arrivals("SET_POSITION_TARGET_LOCAL_NED") if (s.vx, s.vy) == (0.5, 0.25)]
    # Streamed, each target renewed well within GUID_TIMEOUT (3 s by default): what ArduCopter needs. Not a count: a
    # loaded loop sends fewer than 20 Hz makes in 1 s (the rate: scripts/bench_command_latency.py).
    assert len(moving) >= 2 and max(b - a for a, b in itertools.pairwise(moving)) < 1.5
    assert all(s.coordinate_frame == mavlink.MAV_FRAME_BODY_NED for s in setpoints)
    assert (setpoints[-1].vx, setpoints[-1].vy) == (0.0, 0.0)
    assert fc.last_vector_end == VectorEnd(VectorEndKind.COMPLETED)


async def test_orbit_is_circle_mode_and_hold_is_guided(copter: tuple[MavsdkController, FakeAutopilot],
                                                       caplog: pytest.LogCaptureFixture) -> None:
    fc, fake = copter
    await fc.do_orbit(5.0, 2.0)
    assert ardupilot.CIRCLE_FLIES_THE_THROTTLE in [r.getMessage() for r in caplog.records if r.levelname == "WARNING"]
    params = {
        (m.param_id if isinstance(m.param_id, str) else m.param_id.decode()): m.param_value
        for m in fake.of_type("PARAM_SET")
    }
    assert params["CIRCLE_RADIUS_M"] == 5.0
    assert params["CIRCLE_RATE"] == pytest.approx(22.918, abs=0.01)  # 2 m/s on 5 m
    assert set_modes(fake)[-1] == CIRCLE
    assert not [c for c, _ in fake.commands() if c == mavlink.MAV_CMD_DO_ORBIT]
    await fc.hold()
    assert set_modes(fake)[-1] == GUIDED
    async with asyncio.timeout(5):  # the target is sent without an answer: wait for it to arrive
        while not fake.of_type("SET_POSITION_TARGET_LOCAL_NED"):
            await asyncio.sleep(0.02)
    (target,) = fake.of_type("SET_POSITION_TARGET_LOCAL_NED")
    assert (target.vx, target.vy, target.vz, target.yaw_rate) == (0.0, 0.0, 0.0, 0.0)
