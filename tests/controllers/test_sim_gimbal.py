"""The simulated vehicle's gimbal (gimbal protocol v2) and the real controller driving it through MAVSDK's Gimbal
plugin: discovered, controlled, reported, stopped and released. Movement is read on the simulator's truth channel.
A vehicle without a gimbal is a stand-in autopilot that lists none."""

from __future__ import annotations

import asyncio
import math
from typing import Any

import pytest
from pymavlink.dialects.v20 import common as mavlink

from controllers.errors import NotSupported
from controllers.mavsdk import gimbal as mavsdk_gimbal
from controllers.mavsdk.controller import MavsdkController
from controllers.quaternion import euler, quaternion
from controllers.sim.gimbal import MAX_RATE_DEG_S, NEUTRAL_PITCH_DEG, PITCH_LIMITS_DEG, SimGimbal
from controllers.sim.launcher import SimVehicle, free_udp_port
from tests.controllers.fake_autopilot import FakeAutopilot, UdpLink
from tests.controllers.test_sim_mavsdk import wait_truth
from uav_tui.relays.gimbal import SEND_TIMEOUT_S

ME, OTHER = (245, 190), (1, 42)


def _set_attitude(sender: tuple[int, int], *, q: tuple[float, ...] = (math.nan,) * 4,
                  rates: tuple[float, float] = (math.nan, math.nan),
                  flags: int = 0) -> mavlink.MAVLink_gimbal_manager_set_attitude_message:
    encoder = mavlink.MAVLink(None, srcSystem=sender[0], srcComponent=sender[1])
    msg = encoder.gimbal_manager_set_attitude_encode(1, 1, flags, 1, q, math.nan, *rates)
    return mavlink.MAVLink(None).decode(bytearray(msg.pack(encoder)))  # as received: with its sender


def test_quaternion_and_euler_are_inverse() -> None:
    angles = (0.1, -0.7, 2.5)
    assert euler(quaternion(*angles)) == pytest.approx(angles)


def test_control_is_taken_and_released_and_only_the_controller_steers() -> None:
    gimbal = SimGimbal()
    assert gimbal.configure(*ME, ME) == mavlink.MAV_RESULT_ACCEPTED and gimbal.primary == ME
    assert not gimbal.set_attitude(_set_attitude(OTHER, rates=(1.0, 0.0)), 0.0)  # not in control: ignored
    assert gimbal.set_attitude(_set_attitude(ME, rates=(math.radians(30), math.radians(-60))), 0.0)
    for _ in range(10):
        gimbal.step(0.1)
    assert gimbal.pitch_deg == pytest.approx(NEUTRAL_PITCH_DEG + 30) and gimbal.yaw_deg == pytest.approx(-60)
    gimbal.configure(-3, -3, OTHER)  # "release if mine" from someone else: nothing
    assert gimbal.primary == ME
    gimbal.configure(-3, -3, ME)
    assert gimbal.primary == (0, 0)
    pitch, yaw = gimbal.pitch_deg, gimbal.yaw_deg
    gimbal.step(1.0)
    assert (gimbal.pitch_deg, gimbal.yaw_deg, gimbal.pitch_rate, gimbal.yaw_rate) == (pitch, yaw, 0.0, 0.0)


def test_angles_are_approached_at_the_motor_speed_within_the_limits() -> None:
    gimbal = SimGimbal()
    q = quaternion(0.0, math.radians(80), math.radians(90))  # 80 up is beyond the 30 deg limit
    assert gimbal.set_attitude(_set_attitude(ME, q=q), 0.0)
    gimbal.step(0.1)
    assert gimbal.pitch_rate == pytest.approx(MAX_RATE_DEG_S) and gimbal.yaw_rate == pytest.approx(MAX_RATE_DEG_S)
    for _ in range(20):
        gimbal.step(0.1)
    assert gimbal.pitch_deg == pytest.approx(PITCH_LIMITS_DEG[1]) and gimbal.yaw_deg == pytest.approx(90)
    locked = quaternion(0.0, 0.0, math.radians(100))  # yaw in the earth frame, the nose at 40: 60 right of it
    gimbal.set_attitude(_set_attitude(ME, q=locked, flags=mavlink.GIMBAL_MANAGER_FLAGS_YAW_LOCK), 40.0)
    assert gimbal.setpoint.yaw_deg == pytest.approx(60)


async def test_the_controller_points_the_gimbal_reports_it_and_releases_it(sim_vehicle: SimVehicle) -> None:
    truth = sim_vehicle.truth()
    fc = MavsdkController()
    await fc.connect(sim_vehicle.connection_string)
    reports: list[dict[str, Any]] = []

    async def read() -> None:
        async for update in fc.telemetry():
            if "gimbal_pitch_deg" in update:
                reports.append(update)

    reader = asyncio.create_task(read())
    try:
        await fc.point_gimbal("rate", 30.0, -45.0)
        assert fc.gimbal_controlled
        moving = await wait_truth(truth, lambda s: s["gimbal_controlled"] and s["gimbal_yaw"] < -20, 5.0,
                                    "gimbal turning left")
        assert moving["gimbal_pitch_rate"] == pytest.approx(30.0) and moving["gimbal_yaw_rate"] == pytest.approx(-45)
        await fc.release_gimbal()
        stopped = await wait_truth(truth, lambda s: not s["gimbal_controlled"], 3.0, "control released")
        await asyncio.sleep(0.3)
        still = truth.latest()
        assert still is not None and (still["gimbal_pitch_rate"], still["gimbal_yaw_rate"]) == (0.0, 0.0)
        assert still["gimbal_yaw"] == pytest.approx(stopped["gimbal_yaw"], abs=0.5)  # stopped where it was
        assert not fc.gimbal_controlled
        await fc.point_gimbal("angle", -30.0, 20.0)  # control is taken again
        await wait_truth(truth, lambda s: abs(s["gimbal_pitch"] + 30) < 0.5 and abs(s["gimbal_yaw"] - 20) < 0.5,
                           3.0, "gimbal at -30, 20")
        await asyncio.sleep(0.3)
        last = reports[-1]  # the attitude as telemetry: yaw from north (the vehicle's heading plus the gimbal's)
        heading = truth.latest()["yaw"]  # type: ignore[index]
        assert last["gimbal_pitch_deg"] == pytest.approx(-30, abs=0.5)
        assert (last["gimbal_yaw_deg"] - heading - 20 + 180) % 360 - 180 == pytest.approx(0, abs=1.0)
    finally:
        reader.cancel()
        await asyncio.gather(reader, return_exceptions=True)
        await fc.close()
    await wait_truth(truth, lambda s: not s["gimbal_controlled"], 2.0, "released by close()")


async def test_a_vehicle_without_a_gimbal_is_said_to_have_none_once_discovery_is_over(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """MAVSDK's discovery is counted from the connection: a setpoint after it learns at once (within the relay's
    send timeout, which is shorter than the discovery) that there is no gimbal."""
    monkeypatch.setattr(mavsdk_gimbal, "DISCOVERY_WAIT_S", SEND_TIMEOUT_S + 1.0)
    port = free_udp_port()
    with FakeAutopilot(UdpLink(port), mavlink.MAV_AUTOPILOT_PX4):
        fc = MavsdkController()
        await fc.connect(f"udpin://127.0.0.1:{port}", heartbeat_timeout=5.0)
        try:
            await asyncio.sleep(mavsdk_gimbal.DISCOVERY_WAIT_S)
            async with asyncio.timeout(SEND_TIMEOUT_S):
                with pytest.raises(NotSupported, match="the vehicle has no gimbal MAVSDK can find"):
                    await fc.point_gimbal("rate", 10.0, 0.0)
            assert not fc.gimbal_controlled
        finally:
            await fc.close()
