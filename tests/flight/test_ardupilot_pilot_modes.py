"""On ArduCopter the platform holds in GUIDED, so LOITER and BRAKE (MAVSDK's HOLD) are a pilot's or a
failsafe's: autonomy does not fly from them and the hold at exit leaves them alone.

Through a real UavCore and real MAVSDK against the simulator playing ArduCopter; the pilot flips the
mode switch and holds the throttle at mid-stick on the simulator's truth channel.
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

from controllers.sim.launcher import SimVehicle
from tests.core.flight_helpers import flying_core, moving, setpoints_since
from uav_tui.core import UavCore


@asynccontextmanager
async def pilot_in_loiter(tmp_path: Path) -> AsyncIterator[UavCore]:
    """A core on the simulated ArduCopter, airborne; then the pilot switches to LOITER at mid-stick."""
    with SimVehicle(autopilot="ardupilot") as vehicle:
        async with flying_core(tmp_path, vehicle=vehicle) as core:
            truth = core.truth  # type: ignore[attr-defined]
            await asyncio.to_thread(truth.request, {"cmd": "rc_throttle", "pwm": 1500})
            await asyncio.to_thread(truth.request, {"cmd": "rc_mode", "mode": "LOITER"})
            for _ in range(50):  # the pilot's switch is seen (MAVSDK's HOLD) before the test goes on
                if core.telemetry.snapshot().flight_mode == "HOLD":
                    break
                await asyncio.sleep(0.1)
            assert core.telemetry.snapshot().flight_mode == "HOLD", "the pilot's LOITER never reached telemetry"
            yield core


async def test_autonomy_does_not_fly_from_a_pilots_loiter(tmp_path: Path) -> None:
    async with pilot_in_loiter(tmp_path) as core:
        truth = core.truth  # type: ignore[attr-defined]
        since = (truth.latest() or {})["t_mono_ns"]
        await core.execute("f 1")
        await core.execute("autonomy on")
        await asyncio.sleep(1.5)
        assert core.gate.executed == 0 and core.gate.last_decision == "not executed: vehicle in HOLD mode"
        assert moving(await setpoints_since(truth, since)) == []
        assert truth.latest()["mode"] == "LOITER"


async def test_exit_leaves_a_pilots_loiter_alone(tmp_path: Path) -> None:
    async with pilot_in_loiter(tmp_path) as core:
        truth = core.truth  # type: ignore[attr-defined]
        await core.stop("quit")
        assert any("vehicle left in HOLD mode at exit" in e.message for e in core.events.recent)
        assert truth.wait_latest()["mode"] == "LOITER"
