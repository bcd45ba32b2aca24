"""LANDING_TARGET per autopilot: the geometry, and the message as the autopilot receives it (read on a second link)."""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import AsyncIterator

import numpy as np
import pytest
import pytest_asyncio
from pymavlink.dialects.v20 import common as mavlink

from controllers.autopilots import Autopilot
from controllers.landing_target_message import (
    MAV_FRAME_BODY_FRD,
    MAV_FRAME_LOCAL_NED,
    LandingTargetError,
    LandingTargetFix,
    ardupilot_fields,
    landing_target_fields,
    px4_fields,
    rotation_ned_body,
)
from controllers.mavsdk.controller import MavsdkController
from controllers.sim.landing_target_reader import PadEstimate
from controllers.sim.launcher import SimVehicle
from processors.frame_telemetry import FrameTelemetry
from processors.precision_land import PrecisionLand
from sources import create_source
from sources.ground import default_ground
from sources.sim_geometry import Pose
from sources.sim_render import SimRenderer
from tests.controllers.mavlink_tap import MavlinkTap

NADIR = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
"""A camera looking down, the top of the image to the nose: camera x = body right, y = body back, z = body down."""
FORWARD_30 = np.array([[0.0, -math.sin(math.radians(30)), math.cos(math.radians(30))], [1.0, 0.0, 0.0],
                       [0.0, math.cos(math.radians(30)), math.sin(math.radians(30))]])
"""A camera tilted 30 degrees below the nose."""


def unit(*v: float) -> tuple[float, float, float]:
    x, y, z = np.asarray(v, float) / np.linalg.norm(v)
    return float(x), float(y), float(z)


def test_ardupilot_angles_are_a_downward_cameras_line_of_sight_in_the_body_frame() -> None:
    # The pad 1 m right and 2 m behind, 8 m down, seen by a nadir camera: camera (1, 2, 8).
    fix = LandingTargetFix(0, unit(1.0, 2.0, 8.0), 8.3, NADIR)
    fields = ardupilot_fields(fix, 123)
    assert (fields["frame"], fields["position_valid"], fields["time_usec"]) == (MAV_FRAME_BODY_FRD, 0, 123)
    assert fields["angle_x"] == pytest.approx(math.atan2(1, 8)) and fields["angle_y"] == pytest.approx(math.atan2(2, 8))
    # ArduPilot's own reconstruction (AC_PrecLand_Companion): (-tan(angle_y), tan(angle_x), 1) in FRD.
    los = np.array([-math.tan(fields["angle_y"]), math.tan(fields["angle_x"]), 1.0])
    assert los / np.linalg.norm(los) == pytest.approx(np.array(unit(-2.0, 1.0, 8.0)))
    assert fields["distance"] == 8.3


def test_ardupilot_takes_a_tilted_cameras_target_in_body_terms() -> None:
    fix = LandingTargetFix(0, (0.0, 0.0, 1.0), None, FORWARD_30)  # on the optical axis: 30 deg below the nose
    fields = ardupilot_fields(fix, 0)
    assert fields["angle_x"] == pytest.approx(0.0, abs=1e-12)
    assert fields["angle_y"] == pytest.approx(-math.radians(60))  # ahead: 60 deg from straight down
    assert fields["distance"] == 0.0  # unknown: ArduPilot keeps its rangefinder
    with pytest.raises(LandingTargetError, match="not below"):
        ardupilot_fields(LandingTargetFix(0, unit(0.0, -1.0, 1.0), None, FORWARD_30), 0)  # above the horizon


def test_px4_position_is_the_pads_local_ned_position() -> None:
    pad = np.array([3.0, -2.0, 0.0])
    vehicle, attitude = np.array([1.0, 1.0, -9.0]), (5.0, -8.0, 120.0)
    offset = np.array([0.1, 0.0, 0.05])
    body = rotation_ned_body(*attitude).T @ (pad - vehicle) - offset
    camera = NADIR.T @ body
    fix = LandingTargetFix(0, unit(*camera), float(np.linalg.norm(camera)), NADIR, tuple(offset), attitude,
                           tuple(vehicle))
    fields = px4_fields(fix, 5_000_000)
    assert (fields["frame"], fields["position_valid"]) == (MAV_FRAME_LOCAL_NED, 1)
    assert (fields["x"], fields["y"], fields["z"]) == pytest.approx(tuple(pad), abs=1e-9)


@pytest.mark.parametrize("missing", ["distance_m", "attitude_deg", "position_ned"])
def test_px4_needs_distance_attitude_and_position(missing: str) -> None:
    values = {"distance_m": 8.0, "attitude_deg": (0.0, 0.0, 0.0), "position_ned": (0.0, 0.0, -8.0), missing: None}
    with pytest.raises(LandingTargetError, match=missing.split("_")[0]):
        px4_fields(LandingTargetFix(0, (0.0, 0.0, 1.0), rotation_body_camera=NADIR, **values), 0)


def test_an_unknown_autopilot_is_refused() -> None:
    with pytest.raises(LandingTargetError, match="unknown autopilot"):
        landing_target_fields(Autopilot.UNKNOWN, LandingTargetFix(0, (0.0, 0.0, 1.0), 5.0, NADIR), 0)


# ---- as the autopilot receives it ---------------------------------------------------------------

@pytest_asyncio.fixture
async def tapped(sim_vehicle: SimVehicle) -> AsyncIterator[tuple[MavsdkController, MavlinkTap]]:
    """MavsdkController connected to the simulator through a tap that reads what reaches the autopilot."""
    tap = MavlinkTap(sim_vehicle.mavlink_port)
    fc = MavsdkController()
    try:
        await fc.connect(tap.connection_string)
        yield fc, tap
    finally:
        await fc.close()
        tap.close()


async def send_when_clock_known(fc: MavsdkController, fix: LandingTargetFix) -> dict[str, object]:
    deadline = time.monotonic() + 5.0
    while True:
        try:
            return await fc.send_landing_target(fix)
        except LandingTargetError as exc:
            if "clock is unknown" not in str(exc) or time.monotonic() > deadline:
                raise
            await asyncio.sleep(0.1)


@pytest.mark.parametrize("sim_vehicle", [{"autopilot": "px4"}, {"autopilot": "ardupilot"}], indirect=True,
                         ids=["px4", "ardupilot"])
async def test_landing_target_as_the_autopilot_receives_it(sim_vehicle: SimVehicle,
                                                           tapped: tuple[MavsdkController, MavlinkTap]) -> None:
    fc, tap = tapped
    # The clock offset is the least (receive - boot time) seen: from the first ATTITUDE alone it carries that one
    # message's transport delay (33.6 ms seen under load); in flight it has seconds of them, as here.
    await asyncio.sleep(1.0)
    capture_ns = time.monotonic_ns() - 40_000_000  # a frame captured 40 ms ago
    fix = LandingTargetFix(capture_ns, unit(0.5, -0.8, 7.0), 7.1, NADIR, (0.0, 0.0, 0.0), (2.0, -3.0, 45.0),
                           (4.0, -1.0, -7.0))
    sent = await send_when_clock_known(fc, fix)
    arrived_ns, message = tap.wait_for("LANDING_TARGET")
    received = message.to_dict()
    assert fc.autopilot == sim_vehicle.extra_args[sim_vehicle.extra_args.index("--autopilot") + 1]
    if fc.autopilot is Autopilot.ARDUPILOT:
        assert (received["frame"], received["position_valid"]) == (MAV_FRAME_BODY_FRD, 0)
        # a nadir camera, the top of the image to the nose: ArduPilot's angles are the camera's own
        assert received["angle_x"] == pytest.approx(math.atan2(0.5, 7.0), abs=1e-6)
        assert received["angle_y"] == pytest.approx(math.atan2(-0.8, 7.0), abs=1e-6)
    else:
        assert (received["frame"], received["position_valid"]) == (MAV_FRAME_LOCAL_NED, 1)
        expected = np.array(fix.position_ned) + rotation_ned_body(*fix.attitude_deg) @ (7.1 * fix.direction_body)
        assert (received["x"], received["y"], received["z"]) == pytest.approx(tuple(expected), abs=1e-5)
    assert received["distance"] == pytest.approx(7.1, abs=1e-6)
    assert {key: received[key] for key in ("time_usec", "x", "y", "z")} == pytest.approx(
        {key: sent[key] for key in ("time_usec", "x", "y", "z")}, abs=1e-5)
    # time_usec: the capture on the autopilot's clock (its time_boot_ms against the monotonic clock, from its truth).
    truth = sim_vehicle.truth(subscribe=False)
    try:
        state = truth.request({"cmd": "state"})["state"]
    finally:
        truth.close()
    boot_ns = state["t_mono_ns"] - state["time_boot_ms"] * 1_000_000  # to within the 1 ms of time_boot_ms
    expected_us = (capture_ns - boot_ns) / 1000
    early_ms = (expected_us - received["time_usec"]) / 1000
    assert -1.0 <= early_ms <= 20.0, f"time_usec {early_ms:+.1f} ms from the capture on the autopilot's clock"
    assert received["time_usec"] < (arrived_ns - boot_ns) / 1000  # the capture, not the send


@pytest.mark.parametrize("autopilot", [Autopilot.PX4, Autopilot.ARDUPILOT])
@pytest.mark.parametrize("mount", ["down", "45"], ids=["nadir", "tilted-45"])
def test_the_processors_target_points_each_autopilot_at_the_sim_marker(autopilot: Autopilot, mount: str) -> None:
    """sim: camera -> precision_land -> conversion -> the autopilot's reading: the pad where the simulator put it."""
    tilt = "" if mount == "down" else f"&tilt={mount}"
    camera = create_source(f"sim:?marker=5&marker_size=0.6&marker_at=4,2&noise=0{tilt}")
    model = camera.camera_model()
    renderer = SimRenderer(camera.camera, default_ground(0), marker=camera.marker)
    pose = Pose(n=2.5 if mount == "down" else -2.0, e=1.5, d=-8.0, roll=4.0, pitch=-6.0, yaw=20.0)
    telemetry = {"rel_alt_m": 8.0, "roll_deg": pose.roll, "pitch_deg": pose.pitch, "yaw_deg": pose.yaw}
    tm = FrameTelemetry(lambda image, extra: None)
    tm.camera_model = model
    tm.begin(1, 0, 0, telemetry, 0.1)
    processor = PrecisionLand("4x4_50", 5, 0.6)
    processor.tmMgr = tm
    processor.photo_processing(renderer.render(pose))
    target = processor.getLandingTarget()
    assert target is not None, processor.status
    fix = LandingTargetFix(0, target.direction, target.distance_m, model.rotation_body_camera, model.mount.offset_m,
                           (pose.roll, pose.pitch, pose.yaw), (pose.n, pose.e, pose.d))
    fields = landing_target_fields(autopilot, fix, 0)
    estimate = PadEstimate(ardupilot=autopilot is Autopilot.ARDUPILOT)
    estimate.enabled = True
    message = mavlink.MAVLink_landing_target_message(**{**fields, "q": [1.0, 0.0, 0.0, 0.0]})
    estimate.on_message(message, 0, np.array([pose.n, pose.e, pose.d]),
                        tuple(math.radians(a) for a in (pose.roll, pose.pitch, pose.yaw)))
    pad = estimate.pad(0)
    assert pad is not None
    assert math.dist(pad, (4.0, 2.0)) < 0.02 * target.distance_m, f"{pad} from {target.distance_m:.1f} m"


@pytest.mark.parametrize("autopilot", [Autopilot.PX4, Autopilot.ARDUPILOT])
def test_a_fix_that_gives_fields_that_are_not_finite_is_refused_before_mavlink(autopilot: Autopilot) -> None:
    fix = LandingTargetFix(0, (0.0, 0.0, 1.0), 8.0, NADIR, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (math.inf, 0.0, -8.0))
    if autopilot is Autopilot.ARDUPILOT:
        fix = LandingTargetFix(0, (0.0, 0.0, 1.0), math.nan, NADIR)
    with pytest.raises(LandingTargetError, match="not finite"):
        landing_target_fields(autopilot, fix, 0)
