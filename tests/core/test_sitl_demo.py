"""The README demo (vision-only position hold through the sim: camera) on real PX4 SIH and ArduCopter SITL.

No truth channel on a real SITL: distances come from the autopilot's own position estimate in the
run's telemetry.csv (SIH and ArduPilot's SITL estimate the simulated position to centimetres).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from contextlib import AbstractContextManager
from pathlib import Path

import numpy as np
import pytest

from tests import sitl
from tests.core.demo_flight import DemoRun, fly_demo

pytestmark = pytest.mark.sitl


def estimated_ne(demo: DemoRun, command: str) -> tuple[float, float]:
    """The autopilot's (north, east) when the script ran ``command``, interpolated from telemetry.csv."""
    rows = demo.run.telemetry.dropna(subset=["north_m", "east_m"])
    t = demo.command_t_mono_ns(command)
    times = rows.t_mono_ns.astype("int64").to_numpy()
    return (float(np.interp(t, times, rows.north_m.to_numpy())), float(np.interp(t, times, rows.east_m.to_numpy())))


@pytest.mark.parametrize("launch", [sitl.px4_sih, sitl.arducopter], ids=["px4_sih", "arducopter"])
def test_readme_demo_holds_position_from_the_camera_on_a_real_autopilot(
        launch: Callable[[Path], AbstractContextManager[sitl.Sitl]], tmp_path: Path) -> None:
    workdir = tmp_path / "sitl"
    workdir.mkdir()
    with launch(workdir) as vehicle:
        try:
            demo = fly_demo(vehicle.connection_string, tmp_path, wait_first_s=vehicle.ready_after_s, timeout_s=300)
        except AssertionError as exc:
            raise AssertionError(f"{exc}\n--- {vehicle.name} log ---\n{vehicle.log_tail()}") from None
    # ArduCopter sends no local position before its EKF has an origin: the camera hovers until then.
    drawn = {r["source"]["pose_source"] for r in demo.status if r["telemetry"]["armed"]}
    assert drawn == {"vehicle telemetry"}
    assert max(r["telemetry"]["rel_alt_m"] or 0 for r in demo.status) > 9  # took off to 10 m
    reference, pushed, back = (estimated_ne(demo, c) for c in ("f 1", "autonomy on", "autonomy off"))
    assert math.dist(pushed, reference) > 1.0  # PX4 accelerates more gently than the built-in vehicle
    # PX4 SIH's own estimate strays from its simulated truth by up to 0.5 m and its velocity from the rate of
    # its position by 0.3-0.6 m/s for seconds (its ULog): the hold settles within ~0.4 m of the reference
    assert math.dist(back, reference) < 0.7, f"ended {math.dist(back, reference):.2f} m from the reference"
    assert (demo.run.frames.decision == "executed").sum() > 3
    # The autopilot's UTC time (SYSTEM_TIME) reaches telemetry.csv; a SITL takes it from this computer's clock.
    offsets = demo.run.telemetry["fc_clock_offset_ms"].dropna()
    assert len(offsets) and (offsets.abs() < 2000).all(), offsets.describe()
