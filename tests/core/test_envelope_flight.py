"""The envelope on the built-in vehicle: a processor that only ever says "forward at full speed" stays inside.

Judged on the simulator's truth (where the vehicle really is), sampled all through each flight.
"""

from __future__ import annotations

import asyncio
import math
import os
import re
import signal
import time
from pathlib import Path
from typing import Any

import pytest

from tests.core.flight_helpers import flying_core, moving, setpoints_since, speed, wait_until
from tests.flight.test_envelope import polygon_file
from uav_tui.errors import UavError
from uav_tui.flight.envelope_shape import Polygon

PUSHING_PROCESSOR = '''
class Pushing:
    """Test processor: F1 forward, F2 backward, F3 right, each asking for five times any sane speed with its target
    in view; F4: the target lost (no box, no vector)."""

    def __init__(self):
        self.tmMgr = None
        self.vector = None
        self.box = None

    def photo_processing(self, frame):
        pass

    def customize_processing(self, id):
        self.vector = {1: (5.0, 0.0, 2.0), 2: (-5.0, 0.0, 2.0), 3: (0.0, 5.0, 2.0), 4: None}[id]
        self.box = None if self.vector is None else (60, 40, 40, 40)

    def catch_cmd(self, roi):
        pass

    def getPreparedVector(self):
        return self.vector
'''


def pushing(tmp_path: Path) -> str:
    (tmp_path / "pushing.py").write_text(PUSHING_PROCESSOR)
    return f"{tmp_path / 'pushing.py'}:Pushing"


class Track:
    """The truth's positions, sampled every 20 ms while the flight runs."""

    def __init__(self, truth: Any) -> None:
        self.truth = truth
        self.points: list[tuple[float, float]] = []
        self._task = asyncio.create_task(self._sample())

    async def _sample(self) -> None:
        while True:
            state = self.truth.latest()
            self.points.append((state["n"], state["e"]))
            await asyncio.sleep(0.02)

    def stop(self) -> None:
        self._task.cancel()


def radius(state: dict[str, Any]) -> float:
    return math.hypot(state["n"], state["e"])


async def settle(core: Any, refused_more_than: int, what: str, timeout: float = 60) -> None:
    """Until the gate has refused more vectors than ``refused_more_than`` and the vehicle stands still. The time it
    takes is the machine's: quiet, well inside 25 s; beside a loaded suite (load 7-17) the slide into the polygon's
    corner took over 25 s, the vectors arriving late and the vehicle easing along the slanted edge."""
    await wait_until(lambda: core.gate.envelope.refused > refused_more_than and speed(core.truth.latest()) < 0.05,
                     timeout, what)


async def test_forward_at_full_speed_stops_on_the_radius_and_from_outside_only_comes_back(tmp_path: Path) -> None:
    async with flying_core(tmp_path, processor=pushing(tmp_path), radius_m=3.0, max_home_height_m=6.0) as core:
        track = Track(core.truth)
        await core.execute("f 1")
        await core.execute("autonomy on")
        await settle(core, 5, "the vehicle to stop at the 3 m radius")
        stopped = radius(core.truth.latest())
        assert max(math.hypot(*p) for p in track.points) <= 3.0, "the vehicle flew beyond the radius"
        assert 2.0 <= stopped <= 3.0
        assert core.gate.executed > 0 and core.gate.envelope.cut > 0
        # at the boundary a vector is refused, or slides along it when the vehicle stands a little off the axis
        assert "the 3 m radius" in core.gate.last_decision and "beyond" not in core.gate.last_decision

        await core.execute("autonomy off")  # the operator flies it out (the envelope set in flight, wind)
        await core.execute("vector 1 0 2")
        await wait_until(lambda: not core.controller.vector_active and speed(core.truth.latest()) < 0.05, 10,
                         "the operator's vector to end")
        outside = radius(core.truth.latest())
        assert outside > 3.5
        for key, what in (("f 1", "forward: further out"), ("f 3", "right: along the boundary")):
            await core.execute(key)
            await core.execute("autonomy on")
            await wait_until(lambda before=core.gate.envelope.refused: core.gate.envelope.refused > before + 10, 10,
                             f"{what} refused")
            assert radius(core.truth.latest()) <= outside + 0.05, f"{what} flew"
            assert "outside the 3 m radius: only a vector back in flies" in core.gate.last_decision
            await core.execute("autonomy off")
        track.points.clear()
        await core.execute("f 2")  # backward: back in, then on to the far side of the radius
        await core.execute("autonomy on")
        await wait_until(lambda: radius(core.truth.latest()) < 2.5, 15, "the vehicle back inside")
        await wait_until(lambda: core.truth.latest()["n"] < 0 and speed(core.truth.latest()) < 0.05, 25,
                         "the vehicle to stop at the far side")
        track.stop()
        assert min(n for n, _ in track.points) >= -3.0
        assert radius(core.truth.latest()) >= 2.0

        assert core.gate.enabled  # above the ceiling (an updraft): autonomy ends with height_action, hold
        core.truth.request({"cmd": "teleport", "d": -7.0})
        await wait_until(lambda: not core.gate.enabled, 5, "autonomy to end above the ceiling")
        assert re.fullmatch(r"height 7\.\d m above home is above the ceiling 6 m: HOLD", core.gate.stop_reason)
        await wait_until(lambda: core.truth.latest()["mode"] == "HOLD" and speed(core.truth.latest()) < 0.05, 5,
                         "the hold")


async def test_a_polygon_edge_is_slid_along_into_its_corner_never_through_and_a_lost_target_holds(
        tmp_path: Path) -> None:
    corners = [(5.0, -3.0), (-10.0, -3.0), (-10.0, 10.0), (3.0, 10.0)]  # the north edge slants up to the west
    field = polygon_file(tmp_path / "field.geojson", corners)
    async with flying_core(tmp_path, processor=pushing(tmp_path), polygon=str(field), lost_after_s=1.5) as core:
        track = Track(core.truth)
        await core.execute("f 1")  # forward = north, into the slanted edge
        await core.execute("autonomy on")
        await settle(core, 5, "the vehicle to stop in the corner")
        track.stop()
        shape = Polygon(corners)
        deepest_out = min(shape.nearest(p)[0] for p in track.points)
        assert deepest_out >= -0.05, f"the vehicle went {-deepest_out:.2f} m through the boundary"
        state = core.truth.latest()
        assert math.hypot(state["n"] - 5.0, state["e"] + 3.0) < 1.5, "it did not slide into the corner"

        await core.execute("f 4")  # lost, and found again before lost_after_s
        await asyncio.sleep(0.5)
        seen: list[float] = []  # when a frame last reported the target (a frame in flight may still, after "f 4")
        core.add_frame_listener(lambda r: seen.append(time.monotonic())
                               if (r.outcome.box, r.outcome.vector) != (None, None) else None)
        await core.execute("f 1")
        await asyncio.sleep(1.5)
        assert core.gate.enabled, core.gate.stop_reason
        await core.execute("f 4")
        await wait_until(lambda: not core.gate.enabled, 10, "autonomy to end with the target lost")
        assert time.monotonic() - seen[-1] > 1.5 - 0.05  # the gate stamps the same frame a moment earlier
        assert core.gate.stop_reason == "target lost for 1.5 s: HOLD"
        assert any(e.message == "autonomy OFF: target lost for 1.5 s: HOLD" for e in core.events.recent)


async def test_outside_the_height_band_autonomy_is_refused_and_the_battery_floor_returns_home(
        tmp_path: Path) -> None:
    async with flying_core(tmp_path, processor=pushing(tmp_path), min_height_m=4.0, battery_pct=50.0,
                           battery_minutes=0.5) as core:
        await core.execute("f 1")
        with pytest.raises(UavError, match=r"autonomy refused: height \d\.\d m above the ground \(rangefinder\) is "
                                           "below the floor 4 m"):
            await core.execute("autonomy on")
        await asyncio.sleep(0.3)
        assert core.gate.executed == 0 and speed(core.truth.latest()) < 0.1
        await core.execute("takeoff 5")
        await wait_until(lambda: -core.truth.latest()["d"] > 4.7, 15, "the climb to 5 m")
        await core.execute("autonomy on")
        await wait_until(lambda: any("below the floor 20 %: RTL" in e.message for e in core.events.recent), 30,
                         "the battery floor")
        assert not core.gate.enabled and core.gate.executed > 0
        assert re.fullmatch(r"battery 1\d % below the floor 20 %: RTL", core.gate.stop_reason)
        await wait_until(lambda: core.truth.latest()["mode"] == "RTL", 5, "the return home")


async def test_a_lost_target_with_last_seen_flies_back_to_where_it_was_last_seen_and_holds(tmp_path: Path) -> None:
    async with flying_core(tmp_path, processor=pushing(tmp_path), lost_after_s=1.0, lost_action="last_seen") as core:
        seen: list[tuple[float, float]] = []  # the truth at each frame that reported the target
        core.add_frame_listener(
            lambda r: seen.append((core.truth.latest()["n"], core.truth.latest()["e"]))
            if (r.outcome.box, r.outcome.vector) != (None, None) else None)
        await core.execute("f 3")  # right (east), a box in view
        await core.execute("autonomy on")
        await wait_until(lambda: core.truth.latest()["e"] > 1.0, 10, "the vehicle flying east")
        await core.execute("f 4")  # lost: the running vector carries it on, then it holds
        await wait_until(lambda: not core.gate.enabled, 5, "autonomy to end with the target lost")
        last_seen = seen[-1]
        assert re.fullmatch(r"target lost for 1 s \(last seen at -?\d+\.\d m N, -?\d+\.\d m E\): LAST_SEEN",
                            core.gate.stop_reason), core.gate.stop_reason
        away = math.dist(last_seen, (core.truth.latest()["n"], core.truth.latest()["e"]))
        assert away > 0.5, f"the vehicle was only {away:.2f} m from where it saw the target: nothing to fly back"
        await wait_until(lambda: any(e.message.startswith("back at where the target was last seen")
                                     for e in core.events.recent), 10, "the flight back")
        await wait_until(lambda: speed(core.truth.latest()) < 0.05, 5, "the hold")
        state = core.truth.latest()
        assert math.dist(last_seen, (state["n"], state["e"])) < 0.5
        assert state["mode"] == "HOLD" and not core.controller.vector_active


async def test_flying_back_stops_when_the_link_goes_quiet(tmp_path: Path) -> None:
    """No vector is flown on a position older than ``link_timeout``: frozen mid-way back (SIGSTOP: the link is up,
    nothing answers), the flight back ends saying why, and sends nothing more once the simulator runs again."""
    async with flying_core(tmp_path, processor=pushing(tmp_path), lost_after_s=1.0, lost_action="last_seen",
                           link_timeout=1.0) as core:
        await core.execute("f 3")
        await core.execute("autonomy on")
        await wait_until(lambda: core.truth.latest()["e"] > 1.5, 10, "the vehicle flying east")
        await core.execute("f 4")
        await wait_until(lambda: not core.gate.enabled, 5, "autonomy to end with the target lost")
        sim = core.controller.sim  # type: ignore[union-attr]
        os.kill(sim.pid, signal.SIGSTOP)
        try:
            await wait_until(lambda: any("stopped: the link is quiet" in e.message for e in core.events.recent), 10,
                             "the flight back to stop")
        finally:
            os.kill(sim.pid, signal.SIGCONT)
        resumed_ns = time.monotonic_ns()
        await asyncio.sleep(1.5)
        assert not any(e.message.startswith("back at where") for e in core.events.recent)
        assert not moving(await setpoints_since(core.truth, resumed_ns + 600_000_000))  # the last vector's 0.5 s
