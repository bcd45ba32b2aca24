"""A recorded flight of the built-in simulator over its parked car, and where frames.csv puts the car against where
the simulator has it (test_geolocate_flight.py, scripts/bench_geolocation.py)."""

from __future__ import annotations

import asyncio
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from tests.core.flight_helpers import flying_core, wait_until
from uav_tui.flight.geolocate import OK
from uav_tui.recorded import dataset
from uav_tui.status import CoreStatus

SOURCE = "sim:?fps=15&targets=1&target_speed=0"
"""The sim: camera looking down, with one car parked 6 m north of home."""
CLIMB_MS = 5.0
"""The take-off's climb rate (PX4's MPC_TKO_SPEED at its maximum): 50 m in ~11 s instead of ~34 s."""
LEGS = ("vector 0 2 3", "vector 0 -2 3")
"""Sideways at 2 m/s for 3 s, then back: the vehicle rolls as each leg starts and stops, and flies level between."""
LEG_S = 3.5
"""Each leg's 3 s and half a second to stop."""
FAST_MS = 1.5
"""Horizontal speed above which a frame counts as flying (the legs' 2 m/s)."""
STILL_MS = 0.2
"""Speed (horizontal and vertical) below which a frame at the flight's altitude counts as hovering."""
GOALS_P95_M = {20.0: 1.0, 50.0: 2.0}
"""Issue 39's goals for the geo error's p95 by flight height, metres, with the simulator's perfect attitude."""


@dataclass(frozen=True)
class CarFlight:
    """The recorded flight: ``located`` are the frames geo-located from telemetry interpolated to their capture, with
    the car wholly in view (a car cut by the frame's edge is not centred in its box); ``errors`` their horizontal
    distance from the car and ``ground_m`` the fix's altitude above home (the ground is home's), in metres;
    ``status`` the core's once back hovering, 6 m south of the car."""

    altitude_m: float
    run_dir: Path
    frames: pd.DataFrame
    located: pd.DataFrame
    errors: np.ndarray
    ground_m: np.ndarray
    car_ne: tuple[float, float]
    status: CoreStatus
    legs_ns: int
    """When (time.monotonic_ns()) the first of :data:`LEGS` was sent."""

    def fast(self) -> np.ndarray:
        """Which located frames were flying at over :data:`FAST_MS`."""
        return np.hypot(self.located["vn_ms"], self.located["ve_ms"]).to_numpy(dtype=np.float64) > FAST_MS

    def hovering(self) -> np.ndarray:
        """Which located frames were still, within half a metre of the flight's altitude, before the legs: a frame
        drawn as a leg starts or stops tilts the vehicle, while the telemetry interpolated to it (stamped as it
        arrives, late on a loaded machine) may still say it is still (2.4 m off at 20 m, load 27)."""
        at = self.located
        speed = np.hypot(np.hypot(at["vn_ms"], at["ve_ms"]), at["vd_ms"]).to_numpy(dtype=np.float64)
        before = at["t_mono_ns"].to_numpy(dtype=np.int64) < self.legs_ns
        return (speed < STILL_MS) & (np.abs(at["rel_alt_m"].to_numpy(dtype=np.float64) - self.altitude_m) < 0.5) \
            & before

    def within_stated(self) -> np.ndarray:
        """Which located frames' error is within the uncertainty (1 sigma) the platform stated."""
        return self.errors <= self.located["target_uncertainty_m"].to_numpy(dtype=np.float64)


async def fly_over_the_car(folder: Path, altitude: float, *, hover_s: float = 0.0) -> CarFlight:
    """Climb over home to ``altitude`` (recording, the red-blob detector on the car), settle, hover ``hover_s``, fly
    :data:`LEGS`; the run is recorded in ``folder``."""
    async with flying_core(folder, altitude=altitude, climb_ms=CLIMB_MS, source=SOURCE, record=True,
                           runs_dir=str(folder), max_speed=2.0,
                           processor="tests.recording.recorder_processors:RedCar") as core:
        car_n, car_e, _ = core.source.targets[0].position(0.0)  # type: ignore[attr-defined]
        home = core.controller.sim.home  # type: ignore[union-attr]
        truth = core.truth  # type: ignore[attr-defined]
        def settled() -> bool:  # still at the apex of an overshoot is not settled (a loaded simulator's climb)
            now = truth.latest()
            return math.dist((0, 0, 0), (now["vn"], now["ve"], now["vd"])) < STILL_MS / 2 \
                and abs(-now["d"] - altitude) < 0.25
        await wait_until(settled, 20, "the vehicle to settle at its altitude after its climb")
        await asyncio.sleep(hover_s)
        legs_ns = time.monotonic_ns()
        for command in LEGS:
            await core.execute(command)
            await asyncio.sleep(LEG_S)
        status = core.status()
        run_dir = core.recorder.run_dir  # type: ignore[union-attr]
    frames = dataset.load(run_dir).frames
    whole = (frames["box_x"] > 0) & (frames["box_y"] > 0) & (frames["box_x"] + frames["box_w"] < 640) \
        & (frames["box_y"] + frames["box_h"] < 480)
    located = frames[(frames["target_status"] == OK) & (frames["telemetry"] == "interpolated") & whole]
    local = np.array([home.to_local(*row) for row in located[["target_lat_deg", "target_lon_deg", "target_alt_m"]]
                      .to_numpy(dtype=np.float64)]).reshape(-1, 3)
    errors = np.hypot(local[:, 0] - car_n, local[:, 1] - car_e)
    return CarFlight(altitude, run_dir, frames, located, errors, -local[:, 2], (car_n, car_e), status, legs_ns)
