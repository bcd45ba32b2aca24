"""The reference processors closing the loop through vision on the simulated vehicle and camera.

These prove the sign conventions end to end: the processor's vectors move the simulated vehicle,
which moves the camera image the processor sees next. The simulator runs on its own and the
platform reaches it over MAVLink only (as it reaches PX4 or ArduPilot SITL): the camera's pose
comes from telemetry; the truth channel is read by the test alone.
"""

from __future__ import annotations

import asyncio
import math
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from controllers.sim.launcher import SimVehicle
from sources.sim_geometry import PinholeCamera, Pose, project_ground_point
from tests.core.flight_helpers import RENDERER_STALL_S, flying_core, wait_until, what_happened


def horizontal_distance(a: dict, n: float, e: float) -> float:
    return math.hypot(a["n"] - n, a["e"] - e)


async def test_position_hold_brings_the_vehicle_back_and_holds_it_against_wind(tmp_path: Path,
                                                                               sim_vehicle: SimVehicle) -> None:
    async with flying_core(tmp_path, altitude=10, processor="position_hold", source="sim:?width=480&height=360",
                           max_speed=1.5, vehicle=sim_vehicle) as core:
        assert not hasattr(core.controller, "sim")  # MAVLink only: the platform has no truth channel
        assert core.source.get_properties()["pose_source"] == "vehicle telemetry"
        truth = core.truth
        await asyncio.sleep(1.0)
        reference = truth.latest()
        await core.execute("f 1")  # store the reference view
        await core.execute("vector 1 -1 2")  # the operator pushes it away
        await wait_until(lambda: not core.controller.vector_active, 5, "the push to end")
        await asyncio.sleep(1.0)
        pushed = horizontal_distance(truth.latest(), reference["n"], reference["e"])
        assert pushed > 2.0
        await asyncio.to_thread(truth.request, {"cmd": "set_wind", "n": 1.0, "e": 0.5})
        await core.execute("autonomy on")
        await wait_until(lambda: horizontal_distance(truth.latest(), reference["n"], reference["e"]) < 0.6,
                         20, "position hold to return over the reference")
        worst, end = 0.0, time.monotonic() + 8
        while time.monotonic() < end:  # and it stays there, against the wind, from the camera alone
            worst = max(worst, horizontal_distance(truth.latest(), reference["n"], reference["e"]))
            await asyncio.sleep(0.1)
        assert worst < 1.2, f"drifted {worst:.2f} m from the reference while holding"
        assert core.gate.executed > 5 and core.gate.enabled


def centre_off_car(box: tuple[float, float, float, float] | None,
                   outline: list[tuple[float, float]] | None) -> float | None:
    """Pixels from the box's centre to the car's outline (negative inside); None without a box or outline."""
    if box is None or outline is None:
        return None
    x, y, w, h = box
    return -cv2.pointPolygonTest(np.array(outline, np.float32), (x + w / 2, y + h / 2), True)


def car_outline(target: dict, pose: Pose, camera: PinholeCamera) -> list[tuple[float, float]] | None:
    """The car's four ground corners in the image, or None if one is behind the camera."""
    corners = [project_ground_point(n, e, pose, camera) for n, e in target["corners"]]
    return None if None in corners else corners


def box_over_car(box: tuple[float, float, float, float] | None,
                 outline: list[tuple[float, float]] | None) -> float | None:
    """The box's size in units of the car's drawn size (square roots of the areas of the box and of the
    outline's bounding box: a scale that the car turning does not change much); None without either."""
    if box is None or outline is None:
        return None
    _, _, w, h = cv2.boundingRect(np.array(outline, np.float32))
    return math.sqrt(box[2] * box[3] / max(w * h, 1))


@pytest.mark.parametrize(("processor", "max_size"), [("nanotrack", 1.5), ("csrt", None)], ids=["nanotrack", "csrt"])
async def test_tracker_follows_a_target_driving_on_the_ground(tmp_path: Path, sim_vehicle: SimVehicle,
                                                              processor: str, max_size: float | None) -> None:
    """The box stays on the car and the vehicle keeps it in view while it drives away; nanotrack's box keeps
    the car's size (at most ``max_size`` x the car's drawn size; csrt's grows to about 1.5 x in these 20 s).

    How far behind the vehicle trails is the proportional steering's business (gain 2 at 0.6 m/s on a
    6 m circle settles about 2-2.5 m behind, more when a loaded machine delivers fewer vectors), so the
    distance is bounded by what keeps the car in the frame, not by that lag.
    """
    async with flying_core(tmp_path, altitude=12, processor=processor, processor_args={"gain": 2.0, "max_speed": 1.5},
                           source="sim:?width=480&height=360&targets=1&target_speed=0.6", max_speed=1.5,
                           vehicle=sim_vehicle, camera_stall=RENDERER_STALL_S) as core:
        truth = core.truth
        source = core.source
        target = source.get_properties()["targets"][0]
        await core.execute(f"vector {min(1.5, target['n'] / 4):.2f} {target['e'] / 4:.2f} 4")  # fly over it
        await wait_until(lambda: not core.controller.vector_active, 8, "the approach")
        await asyncio.sleep(1.5)
        pose_dict, target = truth.latest(), source.get_properties()["targets"][0]
        pixel = project_ground_point(target["n"], target["e"], Pose.from_mapping(pose_dict), source.camera)
        assert pixel is not None
        u, v = pixel
        assert 60 < u < 420 and 60 < v < 300, f"target not in view at {pixel}"
        outline = car_outline(target, Pose.from_mapping(pose_dict), source.camera)
        x, y, w, h = cv2.boundingRect(np.array(outline, np.float32))
        await core.execute(f"roi {x} {y} {w} {h}")  # the car, as the operator draws round it
        await core.execute("autonomy on")
        start, first, start_pose = time.monotonic(), source.get_properties()["targets"][0], truth.latest()
        distances, samples = [], []
        while time.monotonic() - start < 20:
            props, pose = source.get_properties(), truth.latest()
            t = props["targets"][0]
            distances.append(horizontal_distance(pose, t["n"], t["e"]))
            # the car's outline in the newest frame (the pose and instant it was drawn with); the box is from
            # the newest processed frame, at most a frame or two older: its centre may be 20 px off the car
            box = core.worker.last.outcome.box
            outline = car_outline(t, Pose.from_mapping(props["pose"]), source.camera)
            off, size = centre_off_car(box, outline), box_over_car(box, outline)
            samples.append((off, size, f"{time.monotonic() - start:.1f} s: box {box}, {off and round(off)} px off, "
                                       f"{size and round(size, 2)} x the car"))
            await asyncio.sleep(0.2)
        moved = math.hypot(t["n"] - first["n"], t["e"] - first["e"])
        assert moved > 6  # the target drove well away from where tracking started ...
        assert horizontal_distance(pose, start_pose["n"], start_pose["e"]) > 4, what_happened(core)  # ... it went too
        off_car = [text for off, _, text in samples if off is None or off > 20]
        assert len(off_car) <= 0.1 * len(samples), \
            f"box off the car in {len(off_car)} samples: {off_car}; {what_happened(core)}"
        grown = [text for _, size, text in samples if max_size and size is not None and size > max_size]
        assert not grown, f"the box grew beyond {max_size} x the car: {grown}"
        in_view = 12 * math.tan(math.radians(62 / 2)) * 360 / 480  # ground covered by half the frame's height, m
        assert max(distances) < in_view, \
            f"the car left the frame: distances {distances[-10:]}; {what_happened(core)}"  # ... in view
        tracking = core.worker.last.outcome.box is not None
        assert core.gate.executed > 10 and tracking, what_happened(core)  # still tracking
