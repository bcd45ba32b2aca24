"""Helpers for tests that fly the simulated vehicle through a real UavCore."""

from __future__ import annotations

import asyncio
import math
import os
import subprocess
import sys
import time
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any

from controllers.sim.launcher import SimVehicle
from controllers.sim.truth import TruthClient
from uav_tui.config import Config, load_config
from uav_tui.core import UavCore
from uav_tui.relays.registry import gimbal_relay

STEERING_PROCESSOR = '''
import math, time

class Steering:
    """Test processor: F1 flies (speed forward, side right), F2 hangs, F3 raises, F4 returns NaN;
    catch_cmd sets the speed; every frame takes at least ``delay`` seconds."""

    def __init__(self, speed=0.6, t=2.0, side=0.0, delay=0.0):
        self.tmMgr = None
        self.mode = "idle"
        self.speed = speed
        self.side = side
        self.t = t
        self.delay = delay

    def photo_processing(self, frame):
        time.sleep(self.delay)
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
            return (self.speed, self.side, self.t)
        if self.mode == "nan":
            return (math.nan, 0.0, 1.0)
        return None
'''

NO_FAILSAFE: dict[str, Any] = {"extra_args": ["--offboard-loss-timeout", "600"]}
"""``SimVehicle`` arguments that keep the autopilot's offboard-loss failsafe out of a test: any hold is uav-tui's.
Use as ``@pytest.mark.parametrize("sim_vehicle", [NO_FAILSAFE], indirect=True)``."""


def start_steering_flight(tmp_path: Path, fc: str, script: str, *options: str) -> subprocess.Popen[str]:
    """``uav-tui --no-ui`` flying ``script`` on ``fc`` with the steering processor (text output on stdout)."""
    (tmp_path / "steering.py").write_text(STEERING_PROCESSOR)
    (tmp_path / "flight.txt").write_text(script)
    return subprocess.Popen(
        [sys.executable, "-m", "uav_tui", "--no-ui", "--fc", fc, "--source", "synthetic:?width=160&height=120",
         "--processor", "steering.py:Steering", "--script", "flight.txt", "--no-record", *options],
        cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])},
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def speed(truth: dict[str, Any]) -> float:
    return math.hypot(truth["vn"], truth["ve"])


def wait_for(condition: Callable[[], Any], timeout: float, what: str) -> None:
    """Blocking twin of :func:`wait_until`, for tests that drive uav-tui as a subprocess."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        time.sleep(0.02)


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


def steering_config(tmp_path: Path, *, vehicle: SimVehicle | None = None, **overrides: Any) -> Config:
    """A run's config: the steering test processor, a small synthetic camera, the built-in simulator, no recording.

    ``vehicle``: a simulator running on its own, reached over MAVLink only (``fc`` = its udpin:// address);
    by default the core starts its own (``--fc sim``).
    ``overrides`` are config keys (``processor=``, ``source=``, ``fc=``, ``max_t=`` ...).
    """
    processor = tmp_path / "steering.py"
    processor.write_text(STEERING_PROCESSOR)
    fc = vehicle.connection_string if vehicle is not None else "sim"
    settings = {"fc": fc, "source": "synthetic:?width=160&height=120", "processor": f"{processor}:Steering",
                "record": False, **overrides}
    return load_config(None, settings)


RENDERER_STALL_S = 5.0
"""``camera_stall`` for flights that follow a ``sim:`` target: the simulator's renderer is the camera there, and on a
loaded machine one frame took 0.8-1.7 s to draw (measured beside six busy loops); the watchdog then rightly stops
autonomy, which is not what those tests are about (``test_safety`` tests the stall itself)."""


def what_happened(core: UavCore) -> str:
    """For a failure message: the last frame's box and decisions, the gimbal setpoints and the recent warnings."""
    last, relay = core.last, gimbal_relay(core.relays)
    gimbal = "" if relay is None else f"gimbal setpoints sent {relay.sent}, failed {relay.failed}; "
    frame = "no frame processed" if last is None else (
        f"last frame: box {last.outcome.box}, vector {last.decision!r}, gimbal {last.gimbal!r}")
    warnings = [e.message for e in core.events.recent if e.level != "info"][-8:]
    return f"{gimbal}{frame}; executed {core.gate.executed}; warnings {warnings}"


async def take_off(core: UavCore, truth: TruthClient, altitude: float = 3.0) -> None:
    """Arm and take off through the core's commands; returns once the vehicle holds at ``altitude``."""
    await core.execute("arm")
    await core.execute(f"takeoff {altitude}")
    await wait_until(lambda: (s := truth.latest()) and -s["d"] > altitude - 0.3 and s["mode"] in ("HOLD", "GUIDED"),
                     30, f"takeoff to {altitude} m")  # GUIDED: the simulator playing ArduCopter
    await wait_until(lambda: core.telemetry.snapshot().in_air, 5, "in-air telemetry")


@asynccontextmanager
async def flying_core(tmp_path: Path, *, altitude: float = 3.0, climb_ms: float | None = None,
                      truth: TruthClient | None = None, vehicle: SimVehicle | None = None,
                      **overrides: Any) -> AsyncIterator[UavCore]:
    """A core on the simulated vehicle, airborne at ``altitude``; by default with the steering test processor.

    ``climb_ms``: the take-off's climb rate (PX4's MPC_TKO_SPEED, set over MAVLink before it; the simulator's
    default is PX4's 1.5 m/s), for flights high enough that the climb would be most of the test.
    ``core.truth`` is the simulator's ground truth: the built-in simulator's, ``vehicle``'s (a simulator
    reached over MAVLink only), or ``truth`` when ``fc=`` names a simulator the test started itself
    (one that outlives the core). ``overrides``: see :func:`steering_config`.
    """
    core = UavCore(steering_config(tmp_path, vehicle=vehicle, **overrides))
    await core.start()
    try:
        truth = truth or (vehicle.truth() if vehicle is not None else core.controller.sim.truth())
        core.truth = truth  # type: ignore[attr-defined]
        if climb_ms is not None:
            await core.controller._param.set_param_float("MPC_TKO_SPEED", climb_ms)  # type: ignore[union-attr]
        await take_off(core, truth, altitude)
        yield core
    finally:
        await core.stop("test finished")


async def setpoints_since(truth: TruthClient, since_mono_ns: int) -> list[dict[str, Any]]:
    """Every offboard setpoint the simulator received after ``since_mono_ns`` (time.monotonic_ns())."""
    reply = await asyncio.to_thread(truth.request, {"cmd": "setpoints", "since_mono_ns": since_mono_ns})
    assert not reply["more"], "more setpoints than one reply holds: ask for a shorter span"
    return reply["records"]


def moving(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The setpoints that ask for motion (not the zero that ends a vector)."""
    return [r for r in records if abs(r["vx"]) > 1e-6 or abs(r["vy"]) > 1e-6]
