"""Hold on ArduCopter must not depend on the RC sticks (issue 42, point 0).

ArduCopter's LOITER flies the throttle stick; with it at its minimum (SITL's default RC input, a
transmitter left at idle) a vehicle put in LOITER sinks at the pilot's maximum descent rate. The
built-in simulator in its ``ardupilot`` dialect models exactly that, so these tests fly the platform's
controller (real MAVSDK) against it and read the altitude from the simulator's truth, an independent
source. The same check against real ArduCopter SITL is in ``test_sitl_hold.py``.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import AsyncIterator, Callable

import pytest
import pytest_asyncio

from controllers.autopilots import Autopilot
from controllers.errors import ControllerError
from controllers.mavsdk.controller import MavsdkController
from controllers.sim.launcher import SimVehicle
from controllers.sim.truth import TruthClient
from controllers.vector_end import VectorEnd, VectorEndKind

ALTITUDE_M = 5.0
HOLD_WINDOW_S = 20.0
ALLOWED_DRIFT_M = 0.5


async def altitude_band(altitude: Callable[[], float], seconds: float = HOLD_WINDOW_S) -> tuple[float, float]:
    """The lowest and highest altitude minus the first, sampled at 10 Hz for ``seconds``."""
    start = altitude()
    low = high = 0.0
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        await asyncio.sleep(0.1)
        change = altitude() - start
        low, high = min(low, change), max(high, change)
    return low, high


async def wait_until(condition: Callable[[], bool], timeout_s: float, what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"{what}: not within {timeout_s:g} s")
        await asyncio.sleep(0.05)


@pytest_asyncio.fixture
async def copter() -> AsyncIterator[tuple[MavsdkController, TruthClient]]:
    """The platform's controller on the simulator as an ArduCopter, airborne at ALTITUDE_M in GUIDED."""
    with SimVehicle(autopilot="ardupilot") as sim:
        truth = sim.truth()
        fc = MavsdkController()
        await fc.connect(sim.connection_string, heartbeat_timeout=10.0)
        try:
            assert fc.autopilot is Autopilot.ARDUPILOT
            assert (await fc.check_failsafe(2.0, tune=True)).ok  # as the platform does at connect
            assert await fc.wait_ready(10.0)
            await fc.arm()
            await fc.takeoff(ALTITUDE_M)
            await wait_until(lambda: abs(-truth.wait_latest()["d"] - ALTITUDE_M) < 0.1, 15.0, "take-off altitude")
            yield fc, truth
        finally:
            await fc.close()


def truth_altitude(truth: TruthClient) -> Callable[[], float]:
    return lambda: -truth.wait_latest()["d"]


async def test_the_simulated_loiter_follows_the_throttle_stick(copter: tuple[MavsdkController, TruthClient]) -> None:
    """The model: in LOITER the stick at 1000 sinks at PILOT_SPD_UP (2.5 m/s); at mid-stick it holds."""
    _, truth = copter
    truth.request({"cmd": "teleport", "d": -20.0})  # room to sink (GUIDED holds the new point)
    state = truth.request({"cmd": "rc_mode", "mode": "LOITER"})["state"]  # the pilot flips the mode switch
    assert (state["mode"], state["rc_throttle"]) == ("LOITER", 1000)
    await asyncio.sleep(1.5)
    assert truth.wait_latest()["vd"] == pytest.approx(2.5, abs=0.2)  # still accelerating a little
    truth.request({"cmd": "rc_throttle", "pwm": 1500})
    await asyncio.sleep(3.0)  # braking
    low, high = await altitude_band(truth_altitude(truth), 2.0)
    assert high - low < 0.05


async def test_altitude_kept_after_a_vector_and_after_hold(copter: tuple[MavsdkController, TruthClient]) -> None:
    fc, truth = copter
    await fc.set_fly_vector(1.0, 0.0, 2.0)
    await wait_until(lambda: not fc.vector_active, 10.0, "vector end")
    assert fc.last_vector_end == VectorEnd(VectorEndKind.COMPLETED)
    mode_after_vector = truth.wait_latest()["mode"]
    after_vector = await altitude_band(truth_altitude(truth))

    await fc.hold()
    mode_after_hold = truth.wait_latest()["mode"]
    after_hold = await altitude_band(truth_altitude(truth))

    print(f"simulated ArduCopter: after the vector {after_vector[0]:+.3f}..{after_vector[1]:+.3f} m "
          f"({mode_after_vector}), after hold {after_hold[0]:+.3f}..{after_hold[1]:+.3f} m ({mode_after_hold})")
    assert truth.wait_latest()["rc_throttle"] == 1000  # the stick at its minimum all along
    for what, (low, high), mode in (("after the vector", after_vector, mode_after_vector),
                                    ("after hold", after_hold, mode_after_hold)):
        assert max(-low, high) < ALLOWED_DRIFT_M, (
            f"{what}: altitude moved {low:+.2f}..{high:+.2f} m in {HOLD_WINDOW_S:g} s in {mode}")


async def test_a_vector_sent_as_the_pilot_switches_to_loiter_leaves_the_pilot_in_loiter(
        copter: tuple[MavsdkController, TruthClient]) -> None:
    """The pilot flips to LOITER as autonomy's vector goes out (the gate judged it on the telemetry before the
    switch): the vehicle's own report of LOITER, read right before the switch to GUIDED, wins."""
    fc, truth = copter
    await fc.set_fly_vector(0.5, 0.0, 0.5)  # a vector flown and ended: GUIDED, as autonomy leaves it
    await wait_until(lambda: not fc.vector_active, 10.0, "vector end")
    truth.request({"cmd": "rc_throttle", "pwm": 1500})
    truth.request({"cmd": "rc_mode", "mode": "LOITER"})
    await wait_until(lambda: fc.flight_mode_since(0.0) == "HOLD", 5.0, "the pilot's LOITER reported")
    with pytest.raises(ControllerError, match="in HOLD mode .*not taken back"):
        await fc.set_fly_vector(1.0, 0.0, 2.0, yield_to_others=True)  # before: switched back to GUIDED and flew it
    assert not fc.vector_active
    await asyncio.sleep(1.0)
    assert truth.wait_latest()["mode"] == "LOITER"
