"""``lock ID`` with the camera on the gimbal, on the built-in vehicle: the locked car of the ``sim:`` camera's three is
kept at the picture's centre by the gimbal while the vehicle hovers, judged against the simulator's truth (issue 50)."""

from __future__ import annotations

import asyncio
import time
from pathlib import Path
from typing import Any

from sources.sim_geometry import Pose, project_ground_point
from tests.core.flight_helpers import RENDERER_STALL_S, flying_core, wait_until, what_happened
from uav_tui.flight.track_lock import LockState
from uav_tui.recorded import dataset
from uav_tui.relays.registry import gimbal_relay

WIDTH, HEIGHT = 320, 240
SOURCE = f"sim:?width={WIDTH}&height={HEIGHT}&fps=15&mount=gimbal&targets=3&target_speed=1.0"
"""Three cars on rings of 6, 12 and 18 m round home at 1 m/s, seen by a camera on the gimbal."""
HOVER = {"cmd": "teleport", "n": 0.0, "e": -20.0, "d": -20.0, "yaw": 90.0}
"""20 m up, 20 m west of home facing east: the gimbal, 45 degrees down ahead where it boots, looks at home, and the
6 m ring's car is in the picture wherever it is on its ring."""
CENTRED = 0.1
"""How far from the centre (a share of the frame's width and height) the locked car may be once centred."""
FOLLOW_S = 10.0


def car_pixel(source: Any, car: int) -> tuple[float, float] | None:
    """Where the simulator draws car ``car`` now (the truth), None behind the camera."""
    props = source.get_properties()
    target = props["targets"][car]
    return project_ground_point(target["n"], target["e"], Pose.from_mapping(props["pose"]), source.camera)


async def test_the_gimbal_keeps_the_locked_car_centred_while_the_vehicle_hovers(tmp_path: Path) -> None:
    async with flying_core(tmp_path, altitude=3, source=SOURCE, processor="tests.recording.recorder_processors:RedCars",
                           record=True, runs_dir=str(tmp_path), camera_stall=RENDERER_STALL_S) as core:
        truth, source = core.truth, core.source
        assert gimbal_relay(core.relays) is not None, "the built-in vehicle points a gimbal"
        await asyncio.to_thread(truth.request, HOVER)
        await wait_until(lambda: abs(truth.latest()["d"] + 20) < 0.3, 10, "the hover at 20 m")

        hovering_ns = time.monotonic_ns()

        def track_of_car_zero() -> int | None:
            """The track under car 0 on the newest frame, once that frame was captured in the hover."""
            last, pixel = core.worker.last, car_pixel(source, 0)
            fresh = last is not None and last.frame.t_mono_ns > hovering_ns
            return core.lock.track_at(*pixel) if fresh and pixel is not None else None

        await wait_until(lambda: track_of_car_zero() is not None, 10, "the 6 m ring's car tracked in the hover")
        track = track_of_car_zero()
        assert await core.execute(f"lock {track}") == f"locked on track #{track} (car)"
        await core.execute("autonomy on")
        hover, start = truth.latest(), time.monotonic()
        first = source.get_properties()["targets"][0]
        offsets: list[tuple[float, float, str]] = []
        centred_at: float | None = None  # the car starts off centre: the gimbal brings it there first
        while centred_at is None or time.monotonic() - centred_at < FOLLOW_S:
            await asyncio.sleep(0.2)
            assert time.monotonic() - start < 30, f"the gimbal never centred the car; {what_happened(core)}"
            pixel = car_pixel(source, 0)
            assert pixel is not None, "the car is behind the camera"
            du, dv = abs(pixel[0] - WIDTH / 2) / WIDTH, abs(pixel[1] - HEIGHT / 2) / HEIGHT
            if centred_at is None and du <= CENTRED and dv <= CENTRED:
                centred_at = time.monotonic()
            if centred_at is not None:
                offsets.append((du, dv, f"{time.monotonic() - start:.1f} s: car at {pixel[0]:.0f},{pixel[1]:.0f}, "
                                        f"lock {core.lock.status()}"))
        last, turned = source.get_properties()["targets"][0], truth.latest()
        relay = gimbal_relay(core.relays)
        assert relay is not None and relay.sent > 30, what_happened(core)
        assert core.lock.state is LockState.LOCKED and core.gate.executed == 0  # no vector: the vehicle holds
        assert turned["gimbal_controlled"]
        run_dir = core.recorder.run_dir  # type: ignore[union-attr]

    # The car drove round its ring (10 m and more: over 6 m as the crow flies) and the gimbal kept it centred all
    # along, while the vehicle hovered.
    assert abs(complex(last["n"], last["e"]) - complex(first["n"], first["e"])) > 6
    off = [text for du, dv, text in offsets if du > CENTRED or dv > CENTRED]
    assert not off, f"the car was more than {CENTRED:.0%} of the frame off centre: {off[:5]}"
    assert abs(complex(turned["n"], turned["e"]) - complex(hover["n"], hover["e"])) < 0.5
    # Each locked frame's row: the lock's box, its pointing sent, no vector.
    frames = dataset.load(run_dir).frames
    locked = frames[frames["lock_state"] == "locked"]
    assert len(locked) > 30 and (locked["lock_track"] == track).mean() > 0.95
    assert (locked["gimbal"] == "sent").mean() > 0.9 and locked["vx"].isna().all()
