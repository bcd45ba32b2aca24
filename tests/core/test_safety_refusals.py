"""Safety rules of docs/safety.md whose tests hold no real time to a bound: what the gate refuses and when it lets go.

Every test flies through a real UavCore, real MAVSDK and the simulator process (as ``test_safety.py``, whose tests
hold real-time bounds and run alone in CI); their waits are limits on how long to wait for an outcome, not the
outcome, so they run beside other tests.
"""

from __future__ import annotations

import asyncio
import re
import time
from pathlib import Path

from tests.core.flight_helpers import (
    fly_under_autonomy,
    flying_core,
    moving,
    setpoints_since,
    speed,
    steering_config,
    wait_until,
)
from uav_tui.core import UavCore


async def test_rule1_nan_vector_rejected_counted_and_never_flown(tmp_path: Path) -> None:
    async with flying_core(tmp_path) as core:
        await core.execute("f 4")
        await core.execute("autonomy on")
        await wait_until(lambda: core.gate.rejected >= 5, 10, "rejected vectors")
        assert core.status().vectors_rejected >= 5 and core.gate.executed == 0
        assert core.gate.last_decision.startswith("rejected: non-finite")
        assert not core.controller.vector_active
        assert speed(core.truth.latest()) < 0.1
        assert any("non-finite" in e.message for e in core.events.recent)


async def test_rule2_not_in_the_air_means_no_vector(tmp_path: Path) -> None:
    async with flying_core(tmp_path) as core:
        await core.execute("land")
        await wait_until(lambda: not core.telemetry.snapshot().in_air, 20, "landing")
        await core.execute("f 1")
        await core.execute("autonomy on")
        await wait_until(lambda: core.gate.last_decision.startswith("not executed: vehicle"), 5,
                         f"a decision (now {core.gate.last_decision!r}, autonomy {core.gate.enabled})")
        assert core.gate.last_decision in ("not executed: vehicle not in the air", "not executed: vehicle not armed")
        assert core.gate.executed == 0


async def test_rule4_repeated_processor_exceptions_stop_autonomy(tmp_path: Path) -> None:
    async with flying_core(tmp_path, max_processor_errors=3) as core:
        await fly_under_autonomy(core, lambda: core.controller.vector_active, "a running vector")
        await core.execute("f 3")
        await wait_until(lambda: not core.gate.enabled, 5, "autonomy to stop")
        reason = core.status().autonomy_stop_reason
        assert re.search(r"processor raised (\d+) times in a row", reason) and int(reason.split()[2]) >= 3
        assert "simulated algorithm failure" in (core.status().processor_error or "")
        await wait_until(lambda: core.truth.latest()["mode"] == "HOLD" and speed(core.truth.latest()) < 0.15, 5,
                         "zero and hold")


async def test_arm_and_takeoff_switch_autonomy_off_so_the_processor_never_takes_over_the_climb(
    tmp_path: Path,
) -> None:
    core = UavCore(steering_config(tmp_path))
    await core.start()
    try:
        truth = core.controller.sim.truth()
        await core.execute("f 1")
        await core.execute("autonomy on")  # on the ground: accepted, nothing flies
        await wait_until(lambda: core.gate.last_decision == "not executed: vehicle not armed", 5, "a decision")
        await core.execute("arm")
        assert not core.gate.enabled
        await core.execute("autonomy on")
        since = time.monotonic_ns()
        await core.execute("takeoff 3")
        assert not core.gate.enabled and core.gate.stop_reason == "pre-empted by operator command 'takeoff 3.0'"
        await wait_until(lambda: (s := truth.latest()) and -s["d"] > 2.7 and s["mode"] == "HOLD", 30, "takeoff")
        await asyncio.sleep(1.0)  # at altitude, the processor still asks to fly forward
        assert core.gate.executed == 0 and moving(await setpoints_since(truth, since)) == []
        assert truth.latest()["mode"] == "HOLD" and speed(truth.latest()) < 0.1
    finally:
        await core.stop("test finished")
