"""sim: camera pose vs truth at 30 FPS while manoeuvring, the camera fed by MAVLink telemetry only.

The built-in simulator runs on its own; the platform (a real UavCore) reaches it over MAVLink like
PX4 or ArduPilot SITL. For every frame the camera draws, the pose it used is compared with the
simulator's truth at the frame's capture time (truth datagrams interpolated; same monotonic clock).
For comparison, ``truth_channel_latest`` is what the former ``--fc sim`` path drew: the newest truth
datagram at capture. Latency: ``delivery_ms`` is how long after the instant a sample describes it
reached the platform (autopilot clock mapped onto ours), ``extrapolation_ms`` how far past the newest
sample each frame's pose lay.

Flight: take off to 10 m, vector 1 m/s forward, vector back-right, orbit 5 m at 2 m/s (the yaw
swings to face the centre at up to 90 deg/s), hold; steady wind 1.0 N / 0.5 E m/s.

Usage: python scripts/bench_sim_pose.py [--fps 30] [--orbit-s 8]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from controllers.sim.launcher import SimVehicle  # noqa: E402
from tests.core.flight_helpers import flying_core  # noqa: E402
from tests.core.pose_error import FramePoses, TruthHistory, errors, percentiles  # noqa: E402


async def measure_delivery(controller: Any, delays_ns: list[int]) -> None:
    """Append, for every pose sample, how long after the instant it describes it arrived here."""
    async for sample in controller.pose_samples():
        delays_ns.append(time.monotonic_ns() - sample.t_mono_ns)


async def fly(args: argparse.Namespace, vehicle: SimVehicle) -> dict[str, Any]:
    source = f"sim:?fps={args.fps:g}&width=640&height=480&targets=1"
    with tempfile.TemporaryDirectory() as folder:
        async with flying_core(Path(folder), altitude=10, vehicle=vehicle, source=source,
                               processor="template") as core:
            history = TruthHistory(vehicle.truth())
            frames = FramePoses(core.source, core.truth)
            delivery_ns: list[int] = []
            delivery = asyncio.create_task(measure_delivery(core.controller, delivery_ns))
            frames.recording = True
            started = time.monotonic()
            for command, seconds in (("vector 1 0 2", 2.5), ("vector -1 1 2", 2.5), ("orbit 5 2", args.orbit_s),
                                     ("hold", 2.0)):
                await core.execute(command)
                await asyncio.sleep(seconds)
            frames.recording = False
            elapsed = time.monotonic() - started
            delivery.cancel()
            frames.close()
            await asyncio.sleep(0.2)  # the truth just after the last frame, so it interpolates
            history.close()
    telemetry, latest = errors(frames.frames, history.track), errors(frames.frames, history.track, True)
    lead_ms = np.array([f.extrapolated_s * 1000 for f in frames.frames if f.from_vehicle])
    return {
        "frames": len(frames.frames),
        "fps_measured": round(len(frames.frames) / elapsed, 1),
        "frames_without_vehicle_pose": sum(not f.from_vehicle for f in frames.frames),
        "telemetry": {name: percentiles(values) for name, values in telemetry.items()},
        "delivery_ms": percentiles(np.array(delivery_ns) / 1e6, 1),
        "extrapolation_ms": percentiles(lead_ms, 1),
        "truth_channel_latest": {name: percentiles(values) for name, values in latest.items()},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fps", type=float, default=30.0, help="camera frame rate")
    parser.add_argument("--orbit-s", type=float, default=8.0, help="seconds of orbiting")
    args = parser.parse_args()
    with SimVehicle(wind=(1.0, 0.5)) as vehicle:
        result = asyncio.run(fly(args, vehicle))
    print(json.dumps({"benchmark": "sim_pose", "camera": f"sim: 640x480 @ {args.fps:g} fps",
                      "pose_from": "MAVLink LOCAL_POSITION_NED + ATTITUDE @ 50 Hz, interpolated to capture time",
                      "machine": platform.machine(), "cpus": os.cpu_count(), "python": platform.python_version(),
                      **result}, indent=2))


if __name__ == "__main__":
    main()
