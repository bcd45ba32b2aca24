"""Issue 47: landing targets that type-check but cannot be true never move the vehicle off the pad.

The built-in vehicle (PX4 dialect) at 6 m, a marker 2 m north, the ``precision_land`` processor turned hostile in
one of the ways a probe found: each flight either touches down within 0.5 m of the pad (the simulator's truth) or
is held where it was, and what reached the autopilot (an independent MAVLink reader on the wire, not MAVSDK) is
never an impossible target.
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import AsyncIterator
from pathlib import Path

import pytest
import pytest_asyncio

from controllers.sim.launcher import SimVehicle
from tests.controllers.mavlink_tap import MavlinkTap
from tests.core.flight_helpers import flying_core, wait_until
from uav_tui.errors import UavError

PAD_NE = (2.0, 0.0)
ALTITUDE_M = 6.0
MARKER = f"sim:?marker=7&marker_size=1.0&marker_at={PAD_NE[0]:g},{PAD_NE[1]:g}"

HOSTILE = '''
import math
from uav_values.landing_target import LandingTarget
from processors.precision_land import PrecisionLand


class Hostile(PrecisionLand):
    """PrecisionLand whose landing target is made wrong in one way (``kind``)."""

    def __init__(self, kind, **kwargs):
        super().__init__(**kwargs)
        self.kind = kind
        self.first = None

    def getLandingTarget(self):
        target = super().getLandingTarget()
        if self.kind == "first":  # the first target, again and again, without its frame
            if self.first is None and target is not None:
                self.first = LandingTarget(target.direction, target.distance_m)
            return self.first
        if target is None:
            return None
        if self.kind == "1000x":
            return LandingTarget(target.direction, target.distance_m * 1000, target.frame_seq)
        if self.kind == "angle-pi":
            return LandingTarget.from_angles(math.pi, 0.0, target.distance_m, target.frame_seq)
        x, y, z = target.direction
        changed = {"behind": ("direction", (x, y, -z)), "negative": ("distance_m", -target.distance_m),
                   "nan": ("direction", (x, math.nan, z))}[self.kind]
        object.__setattr__(target, *changed)  # after the value type checked it
        return target
'''


@pytest_asyncio.fixture
async def tap(sim_vehicle: SimVehicle) -> AsyncIterator[MavlinkTap]:
    wire = MavlinkTap(sim_vehicle.mavlink_port)
    try:
        yield wire
    finally:
        wire.close()


@pytest.mark.timeout(180)
@pytest.mark.parametrize("sim_vehicle", [{"autopilot": "px4"}], indirect=True)
@pytest.mark.parametrize("kind", ["1000x", "angle-pi", "behind", "negative", "first", "nan"])
async def test_a_hostile_landing_target_lands_on_the_pad_or_holds(tmp_path: Path, sim_vehicle: SimVehicle,
                                                                   tap: MavlinkTap, kind: str) -> None:
    (tmp_path / "hostile.py").write_text(HOSTILE)
    decisions: list[str] = []
    async with flying_core(tmp_path, altitude=ALTITUDE_M, fc=tap.connection_string, truth=sim_vehicle.truth(),
                           source=MARKER, processor=f"{tmp_path / 'hostile.py'}:Hostile",
                           processor_args={"kind": kind, "marker_id": 7, "marker_size_m": 1.0}) as core:
        truth = core.truth  # type: ignore[attr-defined]
        core.add_frame_listener(lambda result: decisions.append(result.landing))
        await wait_until(lambda: len(decisions) >= 45, 30, "45 frames with the marker in view")
        before = truth.latest()
        try:
            await core.execute("precland")
        except UavError as exc:
            refused = str(exc)
            await asyncio.sleep(3.0)
            after = truth.latest()
            moved = math.dist((before["n"], before["e"], before["d"]), (after["n"], after["e"], after["d"]))
            assert moved < 0.5 and after["in_air"], f"precland refused ({refused}) but the vehicle moved {moved:.2f} m"
            assert "landing target" in refused
        else:
            await wait_until(lambda: (s := truth.latest()) and not s["in_air"] and s["d"] > -0.05, 60, "touchdown")
            state = truth.latest()
            miss = math.hypot(state["n"] - PAD_NE[0], state["e"] - PAD_NE[1])
            assert miss < 0.5, f"touched down {miss:.2f} m from the pad"
        status = core.status()
    sent = [m.to_dict() for _, m in tap.to_autopilot if m.get_type() == "LANDING_TARGET"]
    impossible = [m for m in sent if not (0 < m["distance"] < 3 * ALTITUDE_M and math.hypot(m["x"] - PAD_NE[0],
                                                                                              m["y"] - PAD_NE[1]) < 2)]
    assert not impossible, f"{len(impossible)} impossible LANDING_TARGETs reached the autopilot: {impossible[:2]}"
    at_relay = status.landing_targets_refused > 0 and any(d.startswith("refused: ") for d in decisions)
    if kind in ("behind", "negative", "nan"):  # changed after it was built: from the processor's own process the
        assert at_relay or status.pipeline.errors > 0  # wire's check on arrival refuses it first, as that frame's error
    elif kind != "angle-pi":  # that one never leaves the processor: from_angles refuses pi
        assert at_relay
