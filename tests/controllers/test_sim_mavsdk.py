"""The simulated vehicle through real, unmodified MAVSDK 4: it must pass for a PX4 quadrotor.

Movement is measured on the simulator's ground-truth channel, not on what MAVSDK reports.
"""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import AsyncIterator, Callable
from contextlib import aclosing, asynccontextmanager
from dataclasses import dataclass
from typing import Any

import pytest
from mavsdk.asyncio import ComponentType, Configuration, Mavsdk
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.offboard import OffboardAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync
from mavsdk.plugins.action import ActionError, ActionResult, OrbitYawBehavior
from mavsdk.plugins.offboard import VelocityBodyYawspeed
from mavsdk.plugins.telemetry import FlightMode

from controllers.sim.launcher import SimVehicle
from controllers.sim.truth import TruthClient

TAKEOFF_ALT = 1.0


@dataclass
class Drone:
    action: ActionAsync
    telemetry: TelemetryAsync
    offboard: OffboardAsync


@asynccontextmanager
async def connect(sim: SimVehicle) -> AsyncIterator[Drone]:
    """A MAVSDK ground station connected to ``sim``, with health OK."""
    config = Configuration.create_with_component_type(ComponentType.GROUND_STATION)
    async with Mavsdk(config) as mavsdk:
        await mavsdk.add_any_connection(sim.connection_string)
        system = await mavsdk.first_autopilot(timeout_s=10.0)
        assert system is not None, "MAVSDK found no autopilot"
        drone = Drone(ActionAsync(system), TelemetryAsync(system), OffboardAsync(system))
        async with aclosing(drone.telemetry.subscribe_health_all_ok()) as health:
            async with asyncio.timeout(10):
                async for ok in health:
                    if ok:
                        break
        yield drone


async def wait_truth(
    truth: TruthClient, predicate: Callable[[dict[str, Any]], bool], timeout: float, what: str
) -> dict[str, Any]:
    """Poll the truth stream until ``predicate`` holds; fail naming ``what`` and the last state."""
    deadline = time.monotonic() + timeout
    state = truth.latest()
    while time.monotonic() < deadline:
        state = truth.latest()
        if state is not None and predicate(state):
            return state
        await asyncio.sleep(0.02)
    raise AssertionError(f"{what} not reached within {timeout} s; last truth: {state}")


async def take_off(drone: Drone, truth: TruthClient) -> dict[str, Any]:
    await drone.action.set_takeoff_altitude(TAKEOFF_ALT)
    await drone.action.arm()
    await drone.action.takeoff()
    return await wait_truth(
        truth, lambda s: s["mode"] == "HOLD" and abs(-s["d"] - TAKEOFF_ALT) < 0.15, 6.0, "takeoff altitude"
    )


async def test_connects_as_px4_quadrotor_with_telemetry_flowing(sim_vehicle: SimVehicle) -> None:
    async with connect(sim_vehicle) as drone:
        health = await drone.telemetry.health()
        assert health.is_global_position_ok and health.is_home_position_ok and health.is_armable
        assert await drone.telemetry.flight_mode() == FlightMode.HOLD
        assert not await drone.telemetry.armed()
        home = await drone.telemetry.home()
        assert home.latitude_deg == pytest.approx(47.397742, abs=1e-6)
        assert home.absolute_altitude_m == pytest.approx(488.0, abs=0.01)
        stream = drone.telemetry.subscribe_gps_info()  # the first GPS_RAW_INT, not MAVSDK's empty value before it
        async with aclosing(stream), asyncio.timeout(10):
            gps = await anext(g async for g in stream if g.num_satellites)
        assert gps.num_satellites >= 8
        battery = await drone.telemetry.battery()
        assert battery.voltage_v == pytest.approx(16.8, abs=0.1) and battery.remaining_percent > 99.0
        counts: dict[str, int] = {"attitude": 0, "position": 0}

        async def count(name: str, stream: AsyncIterator[object]) -> None:
            async with aclosing(stream):
                async for _ in stream:
                    counts[name] += 1

        tasks = [
            asyncio.create_task(count("attitude", drone.telemetry.subscribe_attitude_euler())),
            asyncio.create_task(count("position", drone.telemetry.subscribe_position())),
        ]
        await asyncio.sleep(0.5)
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
        assert counts["attitude"] >= 10 and counts["position"] >= 4, counts


async def test_arm_takeoff_disarm_refused_in_air_then_land(sim_vehicle: SimVehicle) -> None:
    truth = sim_vehicle.truth()
    async with connect(sim_vehicle) as drone:
        state = await take_off(drone, truth)
        assert state["armed"] and state["in_air"]
        assert await drone.telemetry.in_air()
        with pytest.raises(ActionError) as err:
            await drone.action.disarm()
        assert err.value.result == ActionResult.COMMAND_DENIED
        assert truth.latest()["armed"]
        await drone.action.land()
        await wait_truth(truth, lambda s: not s["armed"] and not s["in_air"], 6.0, "landed and disarmed")
        assert abs(truth.latest()["n"]) < 0.2 and abs(truth.latest()["e"]) < 0.2


async def request(truth: TruthClient, cmd: dict[str, Any]) -> dict[str, Any]:
    reply = await asyncio.to_thread(truth.request, cmd)
    assert reply["ok"], reply
    return reply


@pytest.mark.parametrize("sim_vehicle", [{"extra_args": ["--failsafe-land-after", "1.0",
                                                         "--offboard-loss-action", "5"]}], indirect=True)
async def test_body_velocity_follows_heading_and_setpoint_loss_holds_then_lands(
    sim_vehicle: SimVehicle,
) -> None:
    truth = sim_vehicle.truth()
    async with connect(sim_vehicle) as drone:
        await take_off(drone, truth)
        teleport = {"cmd": "teleport", "n": 0.0, "e": 0.0, "d": -TAKEOFF_ALT, "yaw": 90.0}
        start = (await request(truth, teleport))["state"]
        await drone.offboard.set_velocity_body(VelocityBodyYawspeed(1.0, 0.0, 0.0, 0.0))
        await drone.offboard.start()
        await wait_truth(truth, lambda s: s["mode"] == "OFFBOARD", 1.0, "OFFBOARD")
        await asyncio.sleep(1.5)
        forward = truth.latest()
        await drone.offboard.set_velocity_body(VelocityBodyYawspeed(0.0, 1.0, 0.0, 0.0))
        await asyncio.sleep(1.2)
        right = truth.latest()
    # facing east: forward is east, right is south; altitude and heading held
    assert forward["ve"] == pytest.approx(1.0, abs=0.1) and abs(forward["vn"]) < 0.05
    assert forward["e"] - start["e"] > 0.8 and abs(forward["n"] - start["n"]) < 0.1
    assert right["vn"] == pytest.approx(-1.0, abs=0.15) and abs(right["ve"]) < 0.15
    assert abs(right["d"] - start["d"]) < 0.1 and right["yaw"] == pytest.approx(90.0, abs=1.0)
    # the ground station is gone, so are the setpoints: HOLD (COM_OBL_RC_ACT 5) after COM_OF_LOSS_T, then LAND
    held = await wait_truth(truth, lambda s: s["mode"] != "OFFBOARD", 3.0, "offboard-loss failsafe")
    records = (await request(truth, {"cmd": "setpoints", "since_mono_ns": 0}))["records"]
    assert held["mode"] == "HOLD" and held["in_air"]
    assert records[-1]["frame"] == 8 and records[-1]["vy"] == 1.0  # MAV_FRAME_BODY_NED
    # Each failsafe waits its configured second (on the simulator's clock; how much later it comes is load).
    assert (held["t_mono_ns"] - records[-1]["t_mono_ns"]) / 1e9 >= 1.0
    landing = await wait_truth(truth, lambda s: s["mode"] == "LAND", 5.0, "failsafe LAND")
    assert (landing["t_mono_ns"] - held["t_mono_ns"]) / 1e9 >= 1.0 - 0.05
    await wait_truth(truth, lambda s: s["vd"] > 0.5, 2.0, "descending")


@pytest.mark.parametrize("sim_vehicle", [{"extra_args": ["--rtl-alt", "2.0"]}], indirect=True)
async def test_return_to_launch_climbs_flies_home_and_descends(sim_vehicle: SimVehicle) -> None:
    truth = sim_vehicle.truth()
    async with connect(sim_vehicle) as drone:
        await take_off(drone, truth)
        await request(truth, {"cmd": "teleport", "n": 3.0, "e": -1.0, "d": -TAKEOFF_ALT, "yaw": 0.0})
        await drone.action.return_to_launch()
        max_alt = 0.0

        def landing_at_home(s: dict[str, Any]) -> bool:
            nonlocal max_alt
            max_alt = max(max_alt, -s["d"])
            return s["vd"] > 0.5 and math.hypot(s["n"], s["e"]) < 0.3

        end = await wait_truth(truth, landing_at_home, 12.0, "RTL descending at home")
        assert await drone.telemetry.flight_mode() == FlightMode.RETURN_TO_LAUNCH
    assert end["mode"] == "RTL" and end["in_air"]
    assert max_alt == pytest.approx(2.0, abs=0.2)


async def test_orbit_holds_its_radius_and_shows_as_posctl(sim_vehicle: SimVehicle) -> None:
    truth = sim_vehicle.truth()
    async with connect(sim_vehicle) as drone:
        await take_off(drone, truth)
        # centre 2 m south of the vehicle, so it starts on the circle
        lat, lon, _ = sim_vehicle.home.to_global(-2.0, 0.0, 0.0)
        alt = sim_vehicle.home.alt_m + TAKEOFF_ALT
        await drone.action.do_orbit(2.0, 1.5, OrbitYawBehavior.HOLD_FRONT_TO_CIRCLE_CENTER, lat, lon, alt)
        await wait_truth(truth, lambda s: s["mode"] == "ORBIT", 1.0, "ORBIT")
        await asyncio.sleep(1.0)
        assert await drone.telemetry.flight_mode() == FlightMode.POSCTL
        samples = []
        for _ in range(30):
            await asyncio.sleep(0.05)
            samples.append(truth.latest())
        await drone.action.hold()
        await wait_truth(truth, lambda s: s["mode"] == "HOLD", 1.0, "HOLD after orbit")
    radii = [math.hypot(s["n"] + 2.0, s["e"]) for s in samples]
    speeds = [math.hypot(s["vn"], s["ve"]) for s in samples]
    assert min(radii) > 1.8 and max(radii) < 2.2, radii
    assert sum(speeds) / len(speeds) == pytest.approx(1.5, abs=0.2)
    assert samples[-1]["e"] > samples[0]["e"]  # clockwise from the north of the circle: eastward
    assert all(abs(-s["d"] - TAKEOFF_ALT) < 0.15 for s in samples)
