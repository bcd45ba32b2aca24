"""The height hold's vertical speed, as the built-in vehicle receives it (its truth channel's setpoint log)."""

from __future__ import annotations

import asyncio
import time
from typing import Any

import pytest

from controllers.mavsdk.controller import MavsdkController
from controllers.mavsdk.height_hold import MAX_AGE_S, MAX_CORRECTION_MS
from controllers.sim.launcher import SimVehicle
from tests.controllers.test_mavsdk_controller import arm_when_ready
from tests.core.flight_helpers import wait_until

LOCAL_POSITION_NED = 32


async def vz_since(sim: SimVehicle, since_ns: int) -> list[float]:
    reply: dict[str, Any] = await asyncio.to_thread(sim.truth().request, {"cmd": "setpoints",
                                                                          "since_mono_ns": since_ns})
    return [r["vz"] for r in reply["records"]]


@pytest.mark.parametrize("sim_vehicle", [{"extra_args": ["--offboard-loss-timeout", "600"]}], indirect=True)
async def test_vertical_speed_is_bounded_and_zero_without_a_fresh_position(sim_vehicle: SimVehicle) -> None:
    truth = sim_vehicle.truth()
    fc = MavsdkController()
    await fc.connect(sim_vehicle.connection_string, heartbeat_timeout=5.0)
    try:
        await arm_when_ready(fc)
        await fc.takeoff(3.0)
        await wait_until(lambda: (s := truth.latest()) and s["mode"] == "HOLD" and -s["d"] > 2.8, 20, "takeoff")
        await wait_until(lambda: abs(truth.latest()["vd"]) < 0.02, 10, "the climb to settle")
        held = truth.latest()
        await fc.set_fly_vector(0.5, 0.0, 10.0)
        await asyncio.sleep(0.5)
        level = await vz_since(sim_vehicle, time.monotonic_ns() - 200_000_000)
        await asyncio.to_thread(truth.request, {"cmd": "teleport", "n": held["n"], "e": held["e"],
                                                "d": held["d"] - 2.0, "yaw": held["yaw"]})  # 2 m above the held height
        await asyncio.sleep(0.3)
        above = await vz_since(sim_vehicle, time.monotonic_ns() - 100_000_000)
        await asyncio.to_thread(truth.request, {"cmd": "stream", "msg_id": LOCAL_POSITION_NED, "interval_us": -1})
        await asyncio.sleep(MAX_AGE_S + 0.3)
        blind = await vz_since(sim_vehicle, time.monotonic_ns() - 100_000_000)
        await fc.hold()
    finally:
        await fc.close()
        truth.close()
    assert level and all(abs(vz) < 0.05 for vz in level)  # at the held height: no correction
    assert above and all(vz == pytest.approx(MAX_CORRECTION_MS) for vz in above)  # down, at most 0.5 m/s
    assert blind and all(vz == 0.0 for vz in blind)  # no fresh position: the plain setpoint
