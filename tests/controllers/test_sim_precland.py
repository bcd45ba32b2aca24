"""The simulated vehicle lands on the pad from LANDING_TARGET, as ArduCopter's precision landing does.

The targets are sent as the platform would (MavsdkController.send_landing_target, from what a downward camera at
the vehicle's pose sees of the pad); the landing is judged on the simulator's truth.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import time

import numpy as np
import pytest
from pymavlink.dialects.v20 import common as mavlink

from controllers.landing_target_message import LandingTargetError, LandingTargetFix, rotation_ned_body
from controllers.mavsdk.controller import MavsdkController
from controllers.precland_requirements import PrecisionLandingError
from controllers.sim import px4_modes
from controllers.sim.guidance import Mode
from controllers.sim.landing_target_reader import PadEstimate
from controllers.sim.launcher import SimVehicle
from controllers.sim.physics import Multicopter
from controllers.sim.truth import TruthClient
from tests.controllers.test_landing_target import NADIR
from tests.controllers.test_mavsdk_controller import arm_when_ready

PAD = np.array([3.0, 0.0, 0.0])
"""The pad, 3 m north of home (NED)."""
ALTITUDE_M = 10.0
HALF_FOV_RAD = (math.radians(31.0), math.radians(24.2))
"""A 640x480 camera with a 62-degree horizontal field of view."""


def seen_from(state: dict[str, float]) -> LandingTargetFix | None:
    """What a nadir camera at the truth's pose sees of the pad, or None when it is out of the image."""
    position = np.array([state["n"], state["e"], state["d"]])
    attitude = (state["roll"], state["pitch"], state["yaw"])
    camera = NADIR.T @ rotation_ned_body(*attitude).T @ (PAD - position)
    if camera[2] <= 0 or abs(math.atan2(camera[0], camera[2])) > HALF_FOV_RAD[0] \
            or abs(math.atan2(camera[1], camera[2])) > HALF_FOV_RAD[1]:
        return None
    distance = float(np.linalg.norm(camera))
    direction = tuple(float(c) for c in camera / distance)
    return LandingTargetFix(int(state["t_mono_ns"]), direction, distance, NADIR, (0.0, 0.0, 0.0), attitude,
                            tuple(float(p) for p in position))


async def send_targets(fc: MavsdkController, truth: TruthClient, sent: list[float]) -> None:
    """LANDING_TARGET at 15 Hz while the pad is in view (a camera's pace), until cancelled."""
    while True:
        state = truth.latest()
        fix = seen_from(state) if state is not None and "n" in state else None
        if fix is not None:
            with contextlib.suppress(LandingTargetError):
                await fc.send_landing_target(fix)
                sent.append(time.monotonic())
        await asyncio.sleep(1 / 15)


@pytest.mark.timeout(180)
@pytest.mark.parametrize("sim_vehicle", [
    {"autopilot": "ardupilot", "extra_args": ["--plnd-enabled"], "wind": (1.5, -1.0), "noise": True},
    {"autopilot": "px4", "wind": (1.0, 1.0), "noise": True},
    {"autopilot": "ardupilot"},
], indirect=True, ids=["ardupilot-precland", "px4-precland", "plain-land"])
async def test_lands_on_the_pad_from_landing_targets(sim_vehicle: SimVehicle, request: pytest.FixtureRequest) -> None:
    precise = "plain" not in request.node.callspec.id
    fc = MavsdkController()
    truth = sim_vehicle.truth()
    sent: list[float] = []
    sender: asyncio.Task[None] | None = None
    try:
        await fc.connect(sim_vehicle.connection_string)
        await arm_when_ready(fc)
        await fc.takeoff(ALTITUDE_M)
        async with asyncio.timeout(40):
            while (state := truth.latest()) is None or -state.get("d", 0.0) < ALTITUDE_M - 0.3:
                await asyncio.sleep(0.1)
        sender = asyncio.create_task(send_targets(fc, truth, sent))
        if precise:
            assert (await fc.precision_land()).startswith("precision landing")
        else:
            await fc.land()
        async with asyncio.timeout(60):
            while (state := truth.latest()) is None or state["in_air"] or state["d"] < -0.05:
                await asyncio.sleep(0.1)
    finally:
        if sender is not None:
            sender.cancel()
            await asyncio.gather(sender, return_exceptions=True)
        await fc.close()
        truth.close()
    miss = math.hypot(state["n"] - PAD[0], state["e"] - PAD[1])
    assert len(sent) > 30, "too few landing targets sent: the pad was not in view"
    if precise:
        assert miss < 0.3, f"landed {miss:.2f} m from the pad"
    else:
        assert miss > 2.5, f"a plain LAND came down {miss:.2f} m from the pad: where it was, not on the pad"


@pytest.mark.timeout(60)
@pytest.mark.parametrize("sim_vehicle", [{"autopilot": "ardupilot"}], indirect=True)
async def test_precland_names_the_plnd_parameter_that_is_wrong_and_does_not_land(sim_vehicle: SimVehicle) -> None:
    fc = MavsdkController()
    truth = sim_vehicle.truth()
    try:
        await fc.connect(sim_vehicle.connection_string)
        await arm_when_ready(fc)
        await fc.takeoff(3.0)
        with pytest.raises(PrecisionLandingError, match=r"PLND_ENABLED = 0, precision landing needs PLND_ENABLED = 1"):
            await fc.precision_land()
        await fc._param.set_param_int("PLND_ENABLED", 1)
        await fc._param.set_param_int("PLND_TYPE", 4)
        with pytest.raises(PrecisionLandingError, match=r"PLND_TYPE = 4, .*needs PLND_TYPE = 1 \(companion"):
            await fc.precision_land()
        await asyncio.sleep(1.0)
        state = truth.latest()
        assert state is not None and state["in_air"] and "LAND" not in state["mode"], "a refused precland landed"
        await fc._param.set_param_int("PLND_TYPE", 1)
        assert "PLND_ENABLED=1, PLND_TYPE=1" in await fc.precision_land()
        await asyncio.sleep(1.0)
        state = truth.latest()
        assert state is not None and "LAND" in state["mode"]
    finally:
        await fc.close()
        truth.close()


def landing_target(**fields: float) -> mavlink.MAVLink_landing_target_message:
    values = {"time_usec": 0, "target_num": 0, "frame": mavlink.MAV_FRAME_BODY_FRD, "angle_x": 0.0, "angle_y": 0.0,
              "distance": 0.0, "size_x": 0.0, "size_y": 0.0, "x": 0.0, "y": 0.0, "z": 0.0, "q": [1, 0, 0, 0],
              "type": 2, "position_valid": 0} | fields
    return mavlink.MAVLink_landing_target_message(**values)


def test_ardupilot_reads_angles_in_the_body_frame_and_drops_other_frames() -> None:
    estimate = PadEstimate(ardupilot=True)
    estimate.enabled = True
    above = np.array([1.0, 2.0, -10.0])
    # 2 m ahead and 1 m left of a vehicle facing east at 10 m: angle_x -> right, angle_y -> back.
    message = landing_target(angle_x=math.atan2(-1, 10), angle_y=math.atan2(-2, 10))
    estimate.on_message(message, 1_000, above, (0.0, 0.0, math.radians(90)))
    assert estimate.pad(1_000) == pytest.approx([1.0 + 1.0, 2.0 + 2.0])  # east = forward, north = left
    estimate.on_message(landing_target(frame=mavlink.MAV_FRAME_LOCAL_NED, position_valid=1, x=9.0, y=9.0,
                                       distance=5.0), 2_000, above, (0.0, 0.0, 0.0))
    assert estimate.rejected == 1 and estimate.pad(2_000) == pytest.approx([2.0, 4.0])
    assert estimate.pad(2_000 + 1_100_000_000) is None  # stale after a second


def test_px4_reads_only_a_local_ned_position() -> None:
    estimate = PadEstimate(ardupilot=False)
    estimate.on_message(landing_target(frame=mavlink.MAV_FRAME_LOCAL_NED, position_valid=1, x=3.0, y=-1.0), 0,
                        np.zeros(3), (0.0, 0.0, 0.0))
    assert estimate.pad(0) == pytest.approx([3.0, -1.0])
    estimate.on_message(landing_target(angle_x=0.1), 0, np.zeros(3), (0.0, 0.0, 0.0))  # angles: the IR-LOCK path
    assert estimate.rejected == 1
    assert [record.used for record in estimate.log] == [True, False]


def test_px4_lands_on_the_pad_in_its_precision_land_mode_only() -> None:
    """PX4's NAV_LAND (param 2 is read in missions only) lands where it is; Precision Land (4, 9) on the pad."""
    assert px4_modes.mode_from_command(4, 9) is Mode.PRECLAND
    assert px4_modes.custom_mode(Mode.PRECLAND) == 9 << 24 | 4 << 16
    vehicle = Multicopter()
    vehicle.armed, vehicle.in_air = True, True
    vehicle.pos[:] = (0.0, 0.0, -10.0)
    vehicle.guidance.pad = lambda: np.array([3.0, 0.0])
    vehicle.guidance.land()
    assert np.hypot(*vehicle.guidance.demand()[0][:2]) < 1e-9  # plain LAND: straight down
    vehicle.guidance.land(Mode.PRECLAND)
    north, east, down = vehicle.guidance.demand()[0]
    assert north > 1.0 and abs(east) < 1e-9 and down > 0  # over the pad while descending
