"""This computer's clock against the autopilot's GPS time (SYSTEM_TIME): recorded with the telemetry, and said
once when it is wrong, with how to set it (a Pi in the field has no network time)."""

from __future__ import annotations

from pathlib import Path

import pytest

from controllers.sim.launcher import SimVehicle
from tests.core.flight_helpers import wait_until
from uav_tui.config import load_config
from uav_tui.core import UavCore
from uav_tui.flight.clock_check import duration
from uav_tui.recorded.dataset import load

THREE_DAYS_S = 3 * 86400 + 4 * 3600


def clock_warnings(core: UavCore) -> list[str]:
    return [e.message for e in core.events.recent if "clock" in e.message]


async def run_against(sim: SimVehicle, tmp_path: Path) -> tuple[UavCore, Path]:
    core = UavCore(load_config(None, {"fc": sim.connection_string, "runs_dir": str(tmp_path / "runs"),
                                      "source": "synthetic:?width=160&height=120"}))
    await core.start()
    try:
        await wait_until(lambda: core.telemetry.snapshot().fc_clock_offset_ms is not None, 15,
                         "the autopilot's time")
        await wait_until(lambda: core.telemetry.updates > 200, 15, "more telemetry")
    finally:
        await core.stop()
    return core, core.recorder.run_dir


@pytest.mark.parametrize("sim_vehicle", [{"extra_args": ["--gps-clock-offset", str(THREE_DAYS_S)]}], indirect=True)
async def test_a_clock_days_behind_is_said_once_and_the_offset_recorded(tmp_path: Path, sim_vehicle) -> None:
    core, run_dir = await run_against(sim_vehicle, tmp_path)
    assert clock_warnings(core) == [
        "this computer's clock is 3 d 4 h behind the autopilot's GPS time (no network time?): run folder names and "
        "t_wall_ns use this computer's clock, and telemetry.csv's fc_clock_offset_ms corrects them; to set the "
        f'clock: sudo date -s "@$(( $(date +%s) +{THREE_DAYS_S} ))"']
    offsets = load(run_dir).telemetry["fc_clock_offset_ms"].dropna()
    assert len(offsets) and (abs(offsets - THREE_DAYS_S * 1000) < 500).all(), offsets.describe()


async def test_a_right_clock_is_not_mentioned(tmp_path: Path, sim_vehicle) -> None:
    core, run_dir = await run_against(sim_vehicle, tmp_path)
    assert clock_warnings(core) == []
    assert (abs(load(run_dir).telemetry["fc_clock_offset_ms"].dropna()) < 500).all()


def test_durations_read_as_two_units() -> None:
    assert [duration(s) for s in (45, 750, 7500, THREE_DAYS_S, 86400 + 300)] == [
        "45 s", "12 min 30 s", "2 h 5 min", "3 d 4 h", "1 d 5 min"]
