"""The autopilot's own failsafe is what stops the vehicle when uav-tui dies: uav-tui checks it at connect.

The simulated vehicle starts with a failsafe that is too slow (a dead client's setpoint flown for 10 s,
then a return home): uav-tui sets it, or refuses autonomy when told not to touch the autopilot.
"""

from __future__ import annotations

import signal
import time
from pathlib import Path

import pytest

from controllers.sim.launcher import SimVehicle
from tests.core.flight_helpers import speed, start_steering_flight, wait_for
from uav_tui.config import load_config
from uav_tui.core import UavCore
from uav_tui.errors import UavError

TOO_SLOW = {"extra_args": ["--offboard-loss-timeout", "10", "--offboard-loss-action", "3"]}
MAX_T = 2.0
STALE_LIMIT_S = MAX_T + 0.5
"""The safety goal: never a stale command for longer than max_t + 0.5 s."""


@pytest.mark.parametrize("sim_vehicle", [TOO_SLOW], indirect=True)
async def test_without_tuning_autonomy_is_refused_naming_the_parameter(sim_vehicle: SimVehicle) -> None:
    config = load_config(None, {"fc": sim_vehicle.connection_string, "record": False,
                                "tune_autopilot_failsafe": False, "max_t": MAX_T})
    core = UavCore(config)
    await core.start()
    try:
        with pytest.raises(UavError, match=r"autonomy refused: COM_OF_LOSS_T = 10 .*COM_OBL_RC_ACT = 3 "):
            await core.execute("autonomy on")
        assert not core.gate.enabled
        messages = [e.message for e in core.events.recent]
        assert ("autopilot failsafe: found COM_OF_LOSS_T=10, COM_OBL_RC_ACT=3 (no radio (SYS_STATUS: no RC receiver; "
                "COM_RC_IN_MODE=3))") in messages
    finally:
        await core.stop()


@pytest.mark.parametrize("sim_vehicle", [TOO_SLOW], indirect=True)
def test_after_sigkill_the_vehicle_stops_within_max_t_plus_margin(tmp_path: Path, sim_vehicle: SimVehicle) -> None:
    process = start_steering_flight(tmp_path, sim_vehicle.connection_string,
                                    "arm\ntakeoff 3\nwait 6\nf 1\nautonomy on\nwait 120\n", "--max-t", str(MAX_T))
    truth = sim_vehicle.truth()
    try:
        wait_for(lambda: (s := truth.latest()) is not None and s["mode"] == "OFFBOARD" and speed(s) > 0.3, 40,
                 "uav-tui to fly a vector")
        process.send_signal(signal.SIGKILL)
        out, _ = process.communicate(timeout=10)
        # Both clocks are CLOCK_MONOTONIC: the simulator's stamps are comparable with the time of the kill.
        killed_ns = time.monotonic_ns()
        wait_for(lambda: speed(truth.latest()) < 0.3, 15, "the vehicle to stop")
        stopped = truth.latest()
        records = truth.request({"cmd": "setpoints", "since_mono_ns": killed_ns - 3_000_000_000})["records"]
    finally:
        process.kill()
        truth.close()
    last_setpoint_ns = max(r["t_mono_ns"] for r in records)
    assert (stopped["t_mono_ns"] - last_setpoint_ns) / 1e9 <= STALE_LIMIT_S
    assert stopped["mode"] == "HOLD"  # COM_OBL_RC_ACT 5: it stops where it is, rather than flying home
    assert "set COM_OF_LOSS_T 10 -> 1, COM_OBL_RC_ACT 3 -> 5" in out
