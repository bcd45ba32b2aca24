"""A lost link is an event with its recovery, the status says the telemetry is stale, a dead simulator is named.

The simulator is frozen with SIGSTOP (link gone, process alive) and resumed with SIGCONT; its last
state (on the ground, HOLD, disarmed) stays on screen, marked stale.
"""

from __future__ import annotations

import os
import signal
from pathlib import Path

from controllers.sim.launcher import SimVehicle
from tests.core.flight_helpers import wait_until
from uav_tui.config import load_config
from uav_tui.core import UavCore
from uav_tui.headless import format_status
from uav_tui.recorded.dataset import load


def messages(core: UavCore) -> list[str]:
    return [e.message for e in core.events.recent if e.kind == "link"]


async def test_link_loss_and_recovery_are_events_and_stale_telemetry_is_marked(
        tmp_path: Path, sim_vehicle: SimVehicle) -> None:
    core = UavCore(load_config(None, {"fc": sim_vehicle.connection_string, "runs_dir": str(tmp_path / "runs"),
                                      "source": "synthetic:?width=160&height=120"}))
    await core.start()
    try:
        await wait_until(lambda: core.telemetry.snapshot().flight_mode is not None, 10, "telemetry")
        assert not core.status().link_lost and "stale" not in format_status(core.status(), 1.0)
        os.kill(sim_vehicle.pid, signal.SIGSTOP)
        try:
            await wait_until(lambda: any(m.startswith("link lost") for m in messages(core)), 10, "a link-lost event")
            status = core.status()
            assert status.link_lost
            assert f"LINK LOST, stale: {status.telemetry.flight_mode} disarmed" in format_status(status, 1.0)
        finally:
            os.kill(sim_vehicle.pid, signal.SIGCONT)
        await wait_until(lambda: any(m.startswith("link restored after") for m in messages(core)), 10,
                         "a link-restored event")
        assert not core.status().link_lost
        run_dir = core.recorder.run_dir
    finally:
        await core.stop()
    recorded = load(run_dir).events
    link = recorded[recorded["kind"] == "link"]["message"].tolist()
    assert [m.split(":")[0].split(" after")[0] for m in link] == ["link lost", "link restored"]


async def test_a_dead_simulator_child_is_reported_with_its_signal(tmp_path: Path) -> None:
    core = UavCore(load_config(None, {"fc": "sim", "record": False, "source": "synthetic:?width=160&height=120"}))
    await core.start()
    try:
        os.kill(core.controller.sim.pid, signal.SIGKILL)
        await wait_until(lambda: core.status().vehicle_problem, 10, "the dead simulator to be reported")
        assert core.status().vehicle_problem == "simulator process killed by SIGKILL"
        assert any("built-in simulator process killed by SIGKILL" in m for m in messages(core))
        assert "(simulator process killed by SIGKILL)" in format_status(core.status(), 1.0)
    finally:
        await core.stop()
