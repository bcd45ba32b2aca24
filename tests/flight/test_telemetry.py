"""TelemetryManager: without a vehicle, and fed by the real MAVSDK controller flying the simulator."""

from __future__ import annotations

import asyncio
import logging
import math
import threading
import time
from typing import Any

import numpy as np
import pytest

from controllers.base import TELEMETRY_FIELDS, Telemetry
from controllers.mavsdk.controller import MavsdkController
from controllers.sim.launcher import SimVehicle
from uav_tui.flight.telemetry import TelemetryManager


async def test_without_controller_everything_is_none() -> None:
    tm = TelemetryManager(None)
    await asyncio.wait_for(tm.run(), 1.0)  # returns at once: nothing to consume
    snap = tm.snapshot()
    assert snap == Telemetry()
    assert all(getattr(snap, name) is None for name in TELEMETRY_FIELDS if name not in ("t_mono_ns", "t_wall_ns"))
    assert not tm.link_alive(1.5)


def test_save_without_saver_counts_and_logs_once(caplog: pytest.LogCaptureFixture) -> None:
    tm = TelemetryManager(None)
    frame = np.zeros((4, 4, 3), np.uint8)
    with caplog.at_level(logging.WARNING, logger="uav_tui.flight.telemetry"):
        for _ in range(3):
            tm.save(frame, target=1)
    assert tm.saves_dropped == 3
    assert [r.getMessage() for r in caplog.records].count(
        "TelemetryManager.save(): recording is off, frames are not stored"
    ) == 1


def test_save_forwards_frame_and_extra_from_another_thread() -> None:
    tm = TelemetryManager(None)
    received: list[tuple[Any, dict[str, Any], str]] = []
    tm.saver = lambda frame, extra: received.append((frame, extra, threading.current_thread().name))
    frame = np.zeros((4, 4, 3), np.uint8)
    worker = threading.Thread(target=tm.save, args=(frame,), kwargs={"cx": 3, "label": "car"}, name="processor_0")
    worker.start()
    worker.join()
    assert len(received) == 1
    assert received[0][0] is frame
    assert received[0][1] == {"cx": 3, "label": "car"}
    assert received[0][2] == "processor_0"
    assert tm.saves_dropped == 0


def test_apply_merges_stamps_and_notifies() -> None:
    tm = TelemetryManager(None)
    seen: list[Telemetry] = []
    tm.add_listener(seen.append)
    before = time.monotonic_ns()
    tm.apply({"lat_deg": 47.0, "lon_deg": 8.0})
    tm.apply({"armed": True, "bogus": 1})
    snap = tm.snapshot()
    assert (snap.lat_deg, snap.lon_deg, snap.armed) == (47.0, 8.0, True)
    assert snap.t_mono_ns >= before
    assert abs(snap.t_wall_ns - time.time_ns()) < 5e9
    assert [t.armed for t in seen] == [None, True]
    assert tm.updates == 2


def test_a_failing_listener_does_not_stop_the_others() -> None:
    tm = TelemetryManager(None)
    seen: list[Telemetry] = []

    def broken(_t: Telemetry) -> None:
        raise RuntimeError("listener bug")

    tm.add_listener(broken)
    tm.add_listener(seen.append)
    tm.apply({"battery_v": 12.1})
    tm.apply({"battery_v": 12.0})
    assert [t.battery_v for t in seen] == [12.1, 12.0]
    assert tm.listener_errors == 2


async def test_manager_follows_the_simulated_vehicle_and_notices_link_loss(
    sim_vehicle: SimVehicle, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.WARNING, logger="uav_tui.flight.telemetry")
    fc = MavsdkController()
    await fc.connect(sim_vehicle.connection_string)
    tm = TelemetryManager(fc)
    rows: list[Telemetry] = []
    tm.add_listener(rows.append)
    task = asyncio.create_task(tm.run())
    try:
        await asyncio.sleep(1.5)
        snap = await asyncio.to_thread(tm.snapshot)  # processors read it from their own thread
        assert snap.lat_deg == pytest.approx(sim_vehicle.home.lat_deg, abs=1e-5)
        assert snap.lon_deg == pytest.approx(sim_vehicle.home.lon_deg, abs=1e-5)
        assert snap.rel_alt_m == pytest.approx(0.0, abs=0.2)
        assert snap.armed is False and snap.in_air is False
        assert snap.flight_mode is not None and snap.battery_v is not None and snap.fc_boot_ms is not None
        assert 0.0 <= snap.heartbeat_age_s < 1.5
        assert time.monotonic_ns() - snap.t_mono_ns < 0.5e9
        assert tm.link_alive(1.5)
        assert len(rows) == tm.updates > 20
        assert rows == sorted(rows, key=lambda t: t.t_mono_ns)
        assert caplog.records == []  # every field the controller sends is a Telemetry field

        await asyncio.to_thread(sim_vehicle.stop)
        await asyncio.sleep(2.0)
        assert not tm.link_alive(1.5)
        assert tm.snapshot().heartbeat_age_s > 1.5
    finally:
        await fc.close()
    await asyncio.wait_for(task, 2.0)  # the stream ends when the controller closes


def test_values_that_cannot_be_true_are_none_with_a_reason_said_once(caplog: pytest.LogCaptureFixture) -> None:
    tm = TelemetryManager(None)
    tm.apply({"lat_deg": 47.0, "lon_deg": 8.0, "rel_alt_m": 10.0, "north_m": 1.0, "pitch_deg": 2.0})
    impossible = {"lat_deg": 91.0, "lon_deg": 200.0, "rel_alt_m": 1e7, "abs_alt_m": math.inf, "north_m": math.inf,
                  "pitch_deg": 400.0, "rangefinder_m": -10.0}
    with caplog.at_level(logging.WARNING, logger="uav_tui.flight.telemetry"):
        for _ in range(2):
            latest = tm.apply(impossible)
    assert all(getattr(latest, name) is None for name in impossible)  # not the last true value either
    assert tm.refused["lat_deg"] == "lat_deg 91 is outside [-90, 90]"
    assert tm.refused["north_m"] == "north_m inf is not finite"
    assert tm.refused["rel_alt_m"] == "rel_alt_m 1e+07 is outside [-20000, 20000]"
    assert tm.values_refused == 2 * len(impossible)
    assert len(caplog.records) == len(impossible)  # each field said once
    assert tm.apply({"lat_deg": -33.9, "lon_deg": 151.2}).lat_deg == -33.9
