"""The dashboard shows a lost link: LOST and STALE in the header, loss and recovery in the event log."""

from __future__ import annotations

import os
import signal

from controllers.sim.launcher import SimVehicle
from uav_tui.tui._header import VehicleLine

from .conftest import in_log, started, wait_for


def header_text(app) -> str:
    return str(app.query_one(VehicleLine).render())


async def test_link_loss_and_recovery_in_header_and_event_log(make_app, sim_vehicle: SimVehicle) -> None:
    app = make_app(fc=sim_vehicle.connection_string)
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        await wait_for(pilot, lambda: "disarmed" in header_text(app), what="telemetry in the header")
        assert "STALE" not in header_text(app)
        os.kill(sim_vehicle.pid, signal.SIGSTOP)
        try:
            await wait_for(pilot, lambda: "STALE" in header_text(app), what="STALE in the header")
            assert "LOST" in header_text(app)
            await wait_for(pilot, lambda: in_log(app, "link lost: no heartbeat"), what="link lost in the log")
        finally:
            os.kill(sim_vehicle.pid, signal.SIGCONT)
        await wait_for(pilot, lambda: in_log(app, "link restored after"), what="link restored in the log")
        await wait_for(pilot, lambda: "STALE" not in header_text(app), what="STALE gone from the header")
