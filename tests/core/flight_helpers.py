"""Helpers for tests that fly the simulated vehicle through a real UavCore."""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any

from controllers.sim.launcher import SimVehicle
from uav_tui.config import load_config
from uav_tui.core import UavCore

STEERING_PROCESSOR = '''
import math, time

class Steering:
    """Test processor: F1 flies forward, F2 hangs, F3 raises, F4 returns NaN; catch_cmd sets the speed."""

    def __init__(self, speed=0.6, t=2.0):
        self.tmMgr = None
        self.mode = "idle"
        self.speed = speed
        self.t = t

    def photo_processing(self, frame):
        if self.mode == "hang":
            time.sleep(30)
        if self.mode == "raise":
            raise RuntimeError("simulated algorithm failure")

    def customize_processing(self, id):
        self.mode = {1: "fly", 2: "hang", 3: "raise", 4: "nan"}[id]

    def catch_cmd(self, roi):
        self.speed = roi[2] / 100

    def getPreparedVector(self):
        if self.mode == "fly":
            return (self.speed, 0.0, self.t)
        if self.mode == "nan":
            return (math.nan, 0.0, 1.0)
        return None
'''


def speed(truth: dict[str, Any]) -> float:
    return math.hypot(truth["vn"], truth["ve"])


async def wait_until(condition: Callable[[], Any], timeout: float, what: str) -> float:
    """Poll ``condition`` every 50 ms; returns the seconds it took, fails the test on timeout."""
    start = time.monotonic()
    while not condition():
        if time.monotonic() - start > timeout:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        await asyncio.sleep(0.05)
    return time.monotonic() - start


async def fly_under_autonomy(core: UavCore, until: Callable[[], Any], what: str, timeout: float = 10) -> None:
    """Let the steering processor stream forward vectors with autonomy on, until ``until()`` holds."""
    await core.execute("f 1")
    await core.execute("autonomy on")
    await wait_until(until, timeout, what)


@asynccontextmanager
async def flying_core(tmp_path: Path, *, altitude: float = 3.0, vehicle: SimVehicle | None = None,
                      **overrides: Any) -> AsyncIterator[UavCore]:
    """A core on the simulated vehicle, airborne at ``altitude``; by default with the steering test processor.

    ``vehicle``: a simulator running on its own, reached over MAVLink only (``fc`` = its udpin:// address);
    by default the core starts its own (``--fc sim``). ``core.truth`` reads the vehicle's truth channel.
    ``overrides`` are config keys (``processor=``, ``source=``, ``max_t=`` ...).
    """
    processor = tmp_path / "steering.py"
    processor.write_text(STEERING_PROCESSOR)
    fc = vehicle.connection_string if vehicle is not None else "sim"
    settings = {"fc": fc, "source": "synthetic:?width=160&height=120", "processor": f"{processor}:Steering",
                "record": False, **overrides}
    core = UavCore(load_config(None, settings))
    await core.start()
    try:
        truth = vehicle.truth() if vehicle is not None else core.controller.sim.truth()
        core.truth = truth  # type: ignore[attr-defined]
        await core.execute("arm")
        await core.execute(f"takeoff {altitude}")
        await wait_until(lambda: (s := truth.latest()) and -s["d"] > altitude - 0.3 and s["mode"] == "HOLD",
                         30, f"takeoff to {altitude} m")
        await wait_until(lambda: core.telemetry.snapshot().in_air, 5, "in-air telemetry")
        yield core
    finally:
        await core.stop("test finished")
