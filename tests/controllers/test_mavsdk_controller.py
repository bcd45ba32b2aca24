"""MavsdkController through real MAVSDK 4 against the simulated vehicle process (measured on its truth).

Most flying tests share one airborne vehicle (module scope, to keep the suite short); each starts by
putting it back in HOLD at a known point and heading.
"""

from __future__ import annotations

import asyncio
import gc
import inspect
import math
import time
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass
from typing import Any

import pytest
import pytest_asyncio

from controllers.autopilots import Autopilot
from controllers.mavsdk import calls, controller
from controllers.mavsdk.controller import MavsdkController
from controllers.sim.launcher import SimVehicle
from controllers.sim.truth import TruthClient
from controllers.vector_end import VectorEnd, VectorEndKind
from uav_tui.errors import CommandDenied

pytestmark = pytest.mark.asyncio(loop_scope="module")

ALT_M = 3.0
Truth = dict[str, Any]


@dataclass
class Flight:
    fc: MavsdkController
    sim: SimVehicle
    truth: TruthClient

    def now(self) -> Truth:
        state = self.truth.latest()
        assert state is not None and "n" in state, f"no truth from the simulator: {state}"
        return state

    async def until(self, pred: Callable[[Truth], bool], timeout: float, what: str) -> Truth:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if pred(state := self.now()):
                return state
            await asyncio.sleep(0.02)
        raise AssertionError(f"{what}: not within {timeout} s; truth {self.now()}")

    async def until_truth(self) -> None:
        """Wait for the first truth datagram (the subscribe reply may come first)."""
        for _ in range(3):
            if "n" in await asyncio.to_thread(self.truth.wait_latest, 2.0):
                return

    async def request(self, **cmd: Any) -> dict[str, Any]:
        return await asyncio.to_thread(self.truth.request, cmd, 1.0)

    async def reset(self, yaw_deg: float = 0.0) -> Truth:
        """Hold at (0, 0, -ALT) facing ``yaw_deg``."""
        await self.fc.hold()
        return await self.teleport(0.0, 0.0, yaw_deg)

    async def teleport(self, n: float, e: float, yaw_deg: float) -> Truth:
        """Move the vehicle to (n, e) at its altitude facing ``yaw_deg``; returns the settled truth after."""
        moved = await self.request(cmd="teleport", n=n, e=e, d=self.now()["d"], yaw=yaw_deg)
        after = moved["state"]["t_mono_ns"]

        def settled(s: Truth) -> bool:
            still = math.hypot(s["vn"], s["ve"], s["vd"]) < 0.05
            return s["t_mono_ns"] > after and still and abs(s["yaw"] - yaw_deg) < 1.0

        return await self.until(settled, 3, "teleport")


async def start_flight(sim: SimVehicle) -> Flight:
    """Connect a MavsdkController to a running simulator."""
    fc = MavsdkController()
    await fc.connect(sim.connection_string, heartbeat_timeout=10)
    flight = Flight(fc, sim, sim.truth())
    await flight.until_truth()
    return flight


@pytest_asyncio.fixture(loop_scope="module", scope="module")
async def airborne() -> AsyncIterator[Flight]:
    sim = await asyncio.to_thread(SimVehicle().start)
    flight = await start_flight(sim)
    try:
        assert (await flight.fc.check_failsafe(2.0, tune=True)).ok  # as the platform does at connect: Hold on loss
        await arm_when_ready(flight.fc)
        await flight.fc.takeoff(ALT_M)
        await flight.until(lambda s: -s["d"] > ALT_M - 0.15 and abs(s["vd"]) < 0.1, 15, "takeoff")
        yield flight
    finally:
        await flight.fc.close()
        await asyncio.to_thread(sim.stop)


async def arm_when_ready(fc: MavsdkController) -> None:
    """Arm once the simulator has its GPS fix (it refuses with a reason before)."""
    deadline = time.monotonic() + 10
    while True:
        try:
            await fc.arm()
            return
        except CommandDenied:
            if time.monotonic() > deadline:
                raise
            await asyncio.sleep(0.3)


def body_displacement(before: Truth, after: Truth) -> tuple[float, float]:
    """(forward, right) metres moved, in the frame of ``before``'s heading."""
    dn, de = after["n"] - before["n"], after["e"] - before["e"]
    yaw = math.radians(before["yaw"])
    return dn * math.cos(yaw) + de * math.sin(yaw), -dn * math.sin(yaw) + de * math.cos(yaw)


FAST_KEYS = ("lat_deg", "roll_deg", "vn_ms", "north_m", "rangefinder_m")
"""Documented at 10 Hz (the simulated vehicle has a downward rangefinder)."""
SLOW_KEYS = ("battery_v", "gps_fix", "armed", "flight_mode", "in_air", "health_ok", "heartbeat_age_s")
"""Documented at 1-2 Hz."""


async def test_connect_detects_px4_and_telemetry_arrives_at_documented_rates(sim_vehicle: SimVehicle) -> None:
    flight = await start_flight(sim_vehicle)
    try:
        assert flight.fc.autopilot is Autopilot.PX4
        assert flight.fc.description == f"PX4 via {flight.sim.connection_string}"
        counts: dict[str, int] = {}
        boot_ms: list[int] = []

        async def collect() -> None:
            async for update in flight.fc.telemetry():
                for key in update:
                    counts[key] = counts.get(key, 0) + 1
                if "fc_boot_ms" in update:
                    boot_ms.append(update["fc_boot_ms"])
                if min(counts.get(key, 0) for key in (*FAST_KEYS, *SLOW_KEYS)) >= 3:
                    return

        await asyncio.wait_for(collect(), 20)
        assert flight.fc.heartbeat_age_s() < 1.5
    finally:
        await flight.fc.close()
    # Every field arrives; the fast ones (10 Hz) more often than the slow ones (1-2 Hz). Rates: scripts/bench_*.
    assert min(counts[key] for key in FAST_KEYS) > max(counts[key] for key in SLOW_KEYS if key != "heartbeat_age_s")
    assert boot_ms == sorted(boot_ms) and boot_ms[-1] > boot_ms[0]


def open_mavsdk_subscriptions() -> list[str]:
    """MAVSDK's ``subscribe_*`` generators not closed yet: their unsubscribe is still to run."""
    return [gen.ag_code.co_name for gen in gc.get_objects()
            if inspect.isasyncgen(gen) and gen.ag_frame is not None and gen.ag_code.co_name.startswith("subscribe_")
            and "mavsdk" in gen.ag_code.co_filename]


async def test_close_unsubscribes_everything_before_mavsdk_is_destroyed(
    sim_vehicle: SimVehicle, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An unsubscribe left to the garbage collector ran while MAVSDK was being destroyed: a segfault (seen in CI)."""
    open_at_release: list[list[str]] = []

    async def release(*args: Any) -> None:  # the real one, after a look at what is still subscribed
        open_at_release.append(open_mavsdk_subscriptions())
        await calls.release(*args)

    monkeypatch.setattr(controller, "release", release)
    flight = await start_flight(sim_vehicle)
    for stream in (flight.fc.telemetry(), flight.fc.pose_samples()):
        count = 0
        async for _ in stream:
            count += 1
            if count == 20:
                break  # the stream is left open: Python closes it later, from the garbage collector
    assert open_mavsdk_subscriptions()  # the telemetry, pose, heartbeat and flight-mode streams
    await flight.fc.close()
    assert open_at_release == [[]]


async def test_an_item_that_fails_costs_that_item_and_is_logged_once(
    sim_vehicle: SimVehicle, caplog: pytest.LogCaptureFixture
) -> None:
    flight = await start_flight(sim_vehicle)
    seen: list[Any] = []

    def on_item(message: Any) -> None:  # the first two ATTITUDE messages meet a bug in the handler
        seen.append(message)
        if len(seen) <= 2:
            raise ValueError("a bug in the handler")

    try:
        reader = flight.fc._subscriptions.read(flight.fc._direct.subscribe_message("ATTITUDE"), on_item, "attitude")
        async with asyncio.timeout(10):
            while len(seen) < 5:
                assert not reader.done()
                await asyncio.sleep(0.05)
    finally:
        await flight.fc.close()
    logged = [r for r in caplog.records if r.exc_info and "a bug in the handler" in str(r.exc_info[1])]
    assert len(logged) == 1 and "attitude" in logged[0].getMessage()


# ---- flying (shared airborne vehicle) ------------------------------------------------------------


async def test_takeoff_reaches_the_requested_altitude(airborne: Flight) -> None:
    state = airborne.now()
    assert state["armed"] and state["in_air"]
    assert abs(-state["d"] - ALT_M) < 0.3


async def test_disarm_in_the_air_is_refused_clearly(airborne: Flight) -> None:
    with pytest.raises(CommandDenied) as info:
        await airborne.fc.disarm()
    assert info.value.command == "disarm"
    assert info.value.result == "COMMAND_DENIED"
    assert "land first" in str(info.value)
    assert airborne.now()["armed"]


@pytest.mark.parametrize(
    ("vx", "vy", "yaw_deg", "forward", "right"),
    [
        pytest.param(0.5, 0.0, 0.0, 1.0, 0.0, id="forward-facing-north"),
        pytest.param(0.5, 0.0, 90.0, 1.0, 0.0, id="forward-facing-east"),
        pytest.param(0.0, 0.5, 0.0, 0.0, 1.0, id="right-facing-north"),
    ],
)
async def test_vector_moves_along_the_heading_then_holds(
    airborne: Flight, vx: float, vy: float, yaw_deg: float, forward: float, right: float
) -> None:
    before = await airborne.reset(yaw_deg)
    since = time.monotonic_ns()
    await airborne.fc.set_fly_vector(vx, vy, 2.0)
    assert airborne.fc.vector_active
    await airborne.until(lambda s: s["mode"] == "OFFBOARD", 1.0, "offboard")
    # The simulator reports HOLD when the command arrives, the controller clears vector_active when its ack is back:
    # two processes, so wait for both rather than assume an order between them.
    ended = await airborne.until(
        lambda s: s["mode"] == "HOLD" and not airborne.fc.vector_active, 3.5, "hold after the vector, acknowledged"
    )
    assert airborne.fc.last_vector_end == VectorEnd(VectorEndKind.COMPLETED)
    assert ended["t_mono_ns"] - since < 3.0e9
    after = await airborne.until(lambda s: math.hypot(s["vn"], s["ve"]) < 0.05, 3.0, "stopped")
    moved_forward, moved_right = body_displacement(before, after)
    assert moved_forward == pytest.approx(forward, abs=0.35)
    assert moved_right == pytest.approx(right, abs=0.35)
    assert abs(after["yaw"] - before["yaw"]) < 2.0
    assert abs(after["d"] - before["d"]) < 0.2
    records = (await airborne.request(cmd="setpoints", since_mono_ns=since))["records"]
    moving = [r for r in records if (r["vx"], r["vy"]) == (vx, vy)]
    # Streamed for the whole 2 s (the 20 Hz rate is a real-time bound: tests/core/test_safety.py, run alone).
    assert (moving[-1]["t_mono_ns"] - moving[0]["t_mono_ns"]) / 1e9 > 2.0 - 0.2
    assert (records[-1]["vx"], records[-1]["vy"]) == (0.0, 0.0)  # zero is the last word, then HOLD


async def test_a_new_vector_replaces_the_running_one_without_leaving_offboard(airborne: Flight) -> None:
    before = await airborne.reset(0.0)
    await airborne.fc.set_fly_vector(0.5, 0.0, 1.5)
    await airborne.until(lambda s: s["mode"] == "OFFBOARD", 1.0, "offboard")
    modes: list[str] = []
    replaced = False
    deadline = time.monotonic() + 6.0
    while time.monotonic() < deadline:
        state = airborne.now()
        modes.append(state["mode"])
        if not replaced and len(modes) > 20:  # ~0.4 s in
            await airborne.fc.set_fly_vector(0.0, 0.5, 1.5)
            replaced = True
        if state["mode"] == "HOLD":
            break
        await asyncio.sleep(0.02)
    first_hold = modes.index("HOLD")
    assert set(modes[:first_hold]) == {"OFFBOARD"}, modes
    after = await airborne.until(lambda s: math.hypot(s["vn"], s["ve"]) < 0.05, 3.0, "stopped")
    moved_forward, moved_right = body_displacement(before, after)
    assert moved_forward > 0.15 and moved_right > 0.4


async def test_hold_preempts_a_running_vector(airborne: Flight) -> None:
    await airborne.reset(0.0)
    await airborne.fc.set_fly_vector(0.5, 0.0, 2.0)
    await asyncio.sleep(0.3)
    await airborne.fc.hold()
    assert not airborne.fc.vector_active
    since = time.monotonic_ns()
    await airborne.until(lambda s: s["mode"] == "HOLD", 1.0, "hold")
    await asyncio.sleep(0.5)
    records = (await airborne.request(cmd="setpoints", since_mono_ns=since))["records"]
    assert records == []  # nothing keeps streaming (MAVSDK's own re-sending stopped too)


async def test_a_stalled_loop_stops_the_setpoints_and_the_vehicle_fails_safe(airborne: Flight) -> None:
    """Nothing re-sends setpoints behind our back: when our loop stalls, the vehicle's failsafe holds."""
    await airborne.reset(0.0)
    # Long enough never to end on its own: under load the stream resumed after the 2 s of a shorter one had passed
    # and ended it COMPLETED before it saw the mode change.
    await airborne.fc.set_fly_vector(0.5, 0.0, 30.0)
    await asyncio.sleep(0.3)
    stalled_at = time.monotonic_ns()
    time.sleep(1.5)  # a blocked event loop (the simulator's offboard-loss timeout is 1 s)
    resumed_at = time.monotonic_ns()
    assert airborne.now()["mode"] == "HOLD"
    records = (await airborne.request(cmd="setpoints", since_mono_ns=stalled_at))["records"]
    assert [r for r in records if stalled_at + 0.1e9 < r["t_mono_ns"] < resumed_at - 0.1e9] == []
    for _ in range(100):  # the stream sees the mode change and gives up the vector (its next telemetry)
        if not airborne.fc.vector_active:
            break
        await asyncio.sleep(0.05)
    assert not airborne.fc.vector_active
    assert airborne.fc.last_vector_end == VectorEnd(VectorEndKind.LEFT_OFFBOARD, "HOLD")
    since = time.monotonic_ns()
    await asyncio.sleep(0.3)
    assert (await airborne.request(cmd="setpoints", since_mono_ns=since))["records"] == []
    assert airborne.now()["mode"] == "HOLD"


async def test_orbit_holds_its_radius(airborne: Flight) -> None:
    centre = await airborne.reset(0.0)
    await asyncio.sleep(0.3)  # the orbit centre is the position telemetry reports: let it see the teleport
    await airborne.fc.do_orbit(3.0, 2.0)
    await airborne.until(lambda s: s["mode"] == "ORBIT", 1.0, "orbit mode")
    await asyncio.sleep(3.0)  # fly out to the circle
    radii, bearings = [], []
    for _ in range(20):
        state = airborne.now()
        radii.append(math.hypot(state["n"] - centre["n"], state["e"] - centre["e"]))
        bearings.append(math.atan2(state["e"] - centre["e"], state["n"] - centre["n"]))
        await asyncio.sleep(0.1)
    assert min(radii) > 2.5 and max(radii) < 3.5, radii
    swept = abs(math.remainder(bearings[-1] - bearings[0], math.tau))
    assert swept > 0.6 * (2.0 / 3.0) * 1.9  # ~2 s at 2 m/s on r = 3: ~1.3 rad


async def test_close_during_a_vector_holds_and_stops_streaming(airborne: Flight) -> None:
    await airborne.reset(0.0)
    await airborne.fc.set_fly_vector(0.5, 0.0, 2.0)
    await asyncio.sleep(0.3)
    await airborne.fc.close()
    await airborne.fc.close()  # idempotent
    since = time.monotonic_ns()
    await airborne.until(lambda s: s["mode"] == "HOLD", 0.2, "hold on close")
    await asyncio.sleep(0.5)
    assert (await airborne.request(cmd="setpoints", since_mono_ns=since))["records"] == []


# ---- a whole flight: RTL and land ----------------------------------------------------------------


@pytest.mark.parametrize("sim_vehicle", [{"extra_args": ["--rtl-alt", "2"]}], indirect=True)
async def test_rtl_returns_home_and_land_lands(sim_vehicle: SimVehicle) -> None:
    flight = await start_flight(sim_vehicle)
    try:
        await arm_when_ready(flight.fc)
        await flight.fc.takeoff(2.0)
        await flight.until(lambda s: s["mode"] == "HOLD" and -s["d"] > 1.8, 15, "takeoff")
        await flight.teleport(3.0, -2.0, 0.0)
        await flight.fc.return_to_home()
        home = await flight.until(lambda s: math.hypot(s["n"], s["e"]) < 0.3, 10, "back home")
        assert home["mode"] == "RTL"
        await flight.fc.land()
        await flight.until(lambda s: s["mode"] == "LAND", 1, "land mode")
        await flight.until(lambda s: not s["in_air"], 10, "landed")
    finally:
        await flight.fc.close()
