"""Holds that hold without a pilot (issue 47, point 0), on the built-in vehicle judged by its truth channel.

- After SIGKILL mid-vector the autopilot's own failsafe takes over: with PX4's default offboard-loss action,
  Position mode, and no radio, PX4 SITL sank 4.4 m in 8 s; the simulator plays that (``POSCTL`` sinking at 0.55
  m/s), so uav-tui must have set Hold at connect. ArduCopter's GUIDED stops when the target lapses.
- While vectors fly, the height at which autonomy engaged is held: ``--climb-drift`` plays PX4 SIH, whose velocity
  setpoints with vertical speed 0 climbed 2.7 m in 14 s.

The same flights on the real autopilots: ``test_sitl_failsafe_hold.py``.
"""

from __future__ import annotations

import math
import signal
import time
from pathlib import Path
from typing import Any

import pytest

from controllers.sim.launcher import SimVehicle
from controllers.sim.truth import TruthClient
from tests.core.flight_helpers import speed, start_steering_flight, wait_for

STILL_WINDOW_S = 5.0
MOVED_GOAL_M = 1.0
"""The vehicle moves less than this in the :data:`STILL_WINDOW_S` after it stops."""
SUNK_GOAL_M = 0.5
"""It loses less height than this from the kill to the end of that window."""
AUTONOMY_S = 20.0
HEIGHT_BAND_M = 0.5
"""20 s of autonomy keep the height within this of where autonomy engaged."""

FLIGHT = "arm\ntakeoff 5\nwait 8\nf 1\nautonomy on\nwait 120\n"


def follow(truth: TruthClient, seconds: float) -> list[dict[str, Any]]:
    """Truth samples every 50 ms for ``seconds``."""
    samples, end = [], time.monotonic() + seconds
    while time.monotonic() < end:
        if (state := truth.latest()) is not None:
            samples.append(state)
        time.sleep(0.05)
    return samples


def after_kill(truth: TruthClient) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The first sample below 0.3 m/s, and the samples of the :data:`STILL_WINDOW_S` that follow it."""
    wait_for(lambda: speed(truth.latest()) < 0.3, 15, "the vehicle to stop")
    stopped = truth.latest()
    return stopped, follow(truth, STILL_WINDOW_S)


EXPECTED = {
    "px4": ("HOLD", ["set COM_OBL_RC_ACT 0 -> 5", "no radio (SYS_STATUS: no RC receiver; COM_RC_IN_MODE=3)"]),
    # a pilot's radio: Position mode is kept, and the pilot's centred sticks hold it
    "px4-radio": ("POSCTL", ["radio connected (SYS_STATUS: RC receiver present; COM_RC_IN_MODE=3)"]),
    "ardupilot": ("GUIDED", ["set GUID_TIMEOUT 3 -> 1"]),
}
"""Per case: the mode the vehicle holds in, and what uav-tui said at connect."""


@pytest.mark.parametrize("sim_vehicle", [{}, {"extra_args": ["--radio"]}, {"autopilot": "ardupilot"}],
                         ids=list(EXPECTED), indirect=True)
def test_after_sigkill_the_vehicle_holds_where_it_stopped(tmp_path: Path, sim_vehicle: SimVehicle,
                                                          request: pytest.FixtureRequest) -> None:
    process = start_steering_flight(tmp_path, sim_vehicle.connection_string, FLIGHT)
    truth = sim_vehicle.truth()
    try:
        wait_for(lambda: (s := truth.latest()) is not None and s["mode"] in ("OFFBOARD", "GUIDED") and speed(s) > 0.3
                 and -s["d"] > 4.5, 60, "uav-tui to fly a vector")
        killed = truth.latest()
        process.send_signal(signal.SIGKILL)
        out, _ = process.communicate(timeout=10)
        stopped, window = after_kill(truth)
    finally:
        process.kill()
        truth.close()
    moved = max(math.hypot(s["n"] - stopped["n"], s["e"] - stopped["e"]) for s in window)
    sunk = -killed["d"] - min(-s["d"] for s in [stopped, *window])
    assert moved < MOVED_GOAL_M and sunk < SUNK_GOAL_M, (
        f"moved {moved:.2f} m in {STILL_WINDOW_S:g} s after stopping, sank {sunk:.2f} m, in {window[-1]['mode']}\n"
        f"{out}")
    mode, said = EXPECTED[request.node.callspec.id]
    assert window[-1]["mode"] == mode  # PX4 without a radio: not POSCTL, Position mode with nobody at the sticks
    assert all(text in out for text in said), out


@pytest.mark.parametrize("sim_vehicle", [{"extra_args": ["--climb-drift", "0.2"]}], indirect=True)
def test_autonomy_holds_the_height_it_engaged_at(tmp_path: Path, sim_vehicle: SimVehicle) -> None:
    process = start_steering_flight(tmp_path, sim_vehicle.connection_string, FLIGHT)
    truth = sim_vehicle.truth()
    try:
        wait_for(lambda: (s := truth.latest()) is not None and s["mode"] == "OFFBOARD", 60, "autonomy to engage")
        engaged = truth.latest()
        samples = follow(truth, AUTONOMY_S)
    finally:
        process.kill()
        process.communicate()
        truth.close()
    heights = [-s["d"] - -engaged["d"] for s in samples]
    flown = math.hypot(samples[-1]["n"] - engaged["n"], samples[-1]["e"] - engaged["e"])
    assert flown > 8.0  # 20 s of 0.6 m/s vectors flew
    assert all(s["mode"] == "OFFBOARD" for s in samples)
    assert max(map(abs, heights)) < HEIGHT_BAND_M, f"height {min(heights):+.2f}..{max(heights):+.2f} m"
