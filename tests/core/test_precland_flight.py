"""Issue 38's flight: the built-in simulator (ArduCopter dialect, PLND_ENABLED) at 10 m with a marker 3 m away,
the ``precision_land`` processor on the ``sim:`` camera, ``precland``: it lands on the marker's centre.

The whole path: the processor's getLandingTarget in its own process, the result message, the core building the fix
with the telemetry at the frame's capture, LANDING_TARGET through the real MAVSDK controller, the simulator's
precision landing; judged on the simulator's truth.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from controllers.sim.launcher import SimVehicle
from tests.core.flight_helpers import flying_core, wait_until
from uav_tui.recorded import dataset
from uav_tui.recorded.report import summary

PAD_NE = (3.0, 0.0)
"""The marker's centre, metres north and east of home (the simulator's truth)."""
MARKER = f"sim:?marker=7&marker_size=1.0&marker_at={PAD_NE[0]:g},{PAD_NE[1]:g}"


@pytest.mark.timeout(300)
@pytest.mark.parametrize("sim_vehicle", [{"autopilot": "ardupilot", "extra_args": ["--plnd-enabled"]}],
                         indirect=True)
async def test_precland_lands_within_30_cm_of_the_marker(tmp_path: Path, sim_vehicle: SimVehicle) -> None:
    async with flying_core(tmp_path, vehicle=sim_vehicle, altitude=10.0, source=MARKER, processor="precision_land",
                           processor_args={"marker_id": 7, "marker_size_m": 1.0}, record=True,
                           runs_dir=str(tmp_path / "runs")) as core:
        truth = core.truth  # type: ignore[attr-defined]
        await wait_until(lambda: core.landing.last_seen_ns is not None, 20, "the marker in view")
        assert core.status().landing_targets_sent == 0  # seen, but nothing is sent before the operator asks
        assert "PLND_ENABLED=1" in await core.execute("precland")
        await wait_until(lambda: (s := truth.latest()) and not s["in_air"] and s["d"] > -0.05, 120, "touchdown")
        state = truth.latest()
        await wait_until(lambda: not core.landing.engaged, 20, "precland ended by the disarm")
        status = core.status()
        problems = [e.message for e in core.events.recent if e.level != "info"]
        assert core.recorder is not None
        run_dir = core.recorder.run_dir
    miss = math.hypot(state["n"] - PAD_NE[0], state["e"] - PAD_NE[1])
    assert miss < 0.3, f"landed {miss:.2f} m from the marker's centre"
    assert status.landing_targets_sent > 20 and status.landing_targets_failed == 0
    frames = dataset.load(run_dir).frames
    landing = frames["landing"].fillna("")
    print(f"miss {miss:.3f} m, sent {status.landing_targets_sent}, rows sent {(landing == 'sent').sum()}")
    assert (landing == "sent").sum() >= status.landing_targets_sent  # every send has its frame's row
    assert landing.str.startswith("not sent: precland and autonomy off").any()  # before precland
    # A landing that went as it should ends without a warning, and its summary says what was sent and where it
    # touched down, from home and from the pad (#46; before: "precland off ...: landed and disarmed", a warning).
    assert problems == []
    lines = summary(dataset.load(run_dir)).splitlines()
    assert [line for line in lines if line.startswith("events:")][0].endswith("(0 warnings, 0 errors)")
    sent_line = next(line for line in lines if line.startswith("landing targets:"))
    assert sent_line.startswith(f"landing targets: {(landing == 'sent').sum()} sent, ")
    touchdown = next(line for line in lines if line.startswith("touched down at"))
    north, east = (float(word) for word in re.findall(r"N (-?[\d.]+) E (-?[\d.]+) m from home", touchdown)[0])
    assert math.hypot(north - state["n"], east - state["e"]) < 0.3, touchdown
    pad_miss = float(re.findall(r"([\d.]+) m from the pad", touchdown)[0])
    assert pad_miss < 0.5, touchdown
