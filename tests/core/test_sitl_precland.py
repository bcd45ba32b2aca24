"""Issue 38's flight on real autopilots (``sitl``): ``precland`` on the sim: camera's marker, judged by the autopilot.

``uav-tui --no-ui`` takes off to 10 m over the autopilot's local origin with marker 7 (0.5 m) drawn 3 m north of
it, waits, and runs ``precland``: the ``precision_land`` processor finds the marker, the platform sends
LANDING_TARGET, the autopilot's own precision landing flies the descent. An independent pymavlink client on a
second link reads the autopilot's local position (LOCAL_POSITION_NED): where it was before ``precland`` and where it
touched down (the first position within :data:`GROUND_M` of its height before arming: on the ground PX4 SIH's
estimate goes on wandering, by 0.7-1.2 m in 8 s once landed). The sim: camera's world origin is the autopilot's local
origin, so the landing error is that position's distance from (3, 0).

- ArduCopter SITL, ``PLND_ENABLED=1``, ``PLND_TYPE=1`` (set at boot): LAND with the companion's angles and distance.
- PX4 SIH: the platform switches to PX4's Precision Land mode (:mod:`controllers.precland_requirements`).
  ``PLD_FAPPR_ALT`` 1.5 m: below about 1.2 m the 0.5 m marker leaves the 62-degree camera's view once the vehicle is 0.2
  m off it; with the default 0.1 m PX4 takes the lost target for a lost pad once PLD_BTOUT (5 s) passes before
  touchdown, climbs back to search and starts over (seen once: no touchdown within 180 s).
"""

from __future__ import annotations

import contextlib
import math
import os
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import urlparse

import pytest
from pymavlink import mavutil

from tests import sitl
from uav_tui.recorded import dataset

pytestmark = pytest.mark.sitl

ROOT = Path(__file__).resolve().parents[2]
PAD_NE = (3.0, 0.0)
"""The marker's centre in the autopilot's local frame (north, east), metres."""
GOAL_M = {"arducopter": 0.3, "px4": 1.0}
"""Touchdown within this of the marker's centre. ArduCopter: the issue's bound (measured 0.028 and 0.031 m). PX4
SIH, on this 2-core machine at load average 7-15: 0.15-0.43 m in six runs with its defaults, 0.27 and 0.50 m with
PLD_FAPPR_ALT 1.5 (its estimate wanders: its hover by +-0.4 m, after touchdown by 0.1-1.2 m before the disarm), so
1.0 m; a plain LAND comes down 3 m away, which either bound tells apart."""
LANDING_MODE = {"arducopter": "LAND", "px4": "PRECISION_LAND"}
"""The flight mode the platform records while the autopilot lands precisely (PX4's: UNKNOWN to MAVSDK, named from
the HEARTBEAT by controllers.flight_modes)."""
ALTITUDE_M = 10.0
GROUND_M = 0.15
"""Touchdown: the estimated height above where the vehicle stood before arming first falls below this after the
flight."""
SOURCE = f"sim:?marker=7&marker_size=0.5&marker_at={PAD_NE[0]:g},{PAD_NE[1]:g}"


@dataclass
class Track:
    """What the observer read: the newest local position, the highest point, the position there, and the texts."""

    position: tuple[float, float, float] | None = None
    ground_z: float = 0.0
    """The estimated ``z`` on the ground before arming (PX4 SIH's sits 0.2-0.4 m above its origin)."""
    highest_m: float = 0.0
    """Above :attr:`ground_z`."""
    at_height: tuple[float, float] | None = None
    """(north, east) when the vehicle first was within 0.5 m of the take-off height: before ``precland``."""
    touchdown: tuple[float, float] | None = None
    """(north, east) when it came back within :data:`GROUND_M` of :attr:`ground_z`."""
    armed: bool = False
    landed_disarmed: bool = False
    texts: list[str] = field(default_factory=list)


class Observer:
    """The autopilot's LOCAL_POSITION_NED, HEARTBEAT and STATUSTEXT, read on a second link
    (:class:`tests.sitl.SecondLink`)."""

    def __init__(self, url: str) -> None:
        self.track = Track()
        self.link = sitl.SecondLink(url, 201, "LOCAL_POSITION_NED", ["LOCAL_POSITION_NED", "HEARTBEAT", "STATUSTEXT"],
                                    self._on_message, "precland-observer")

    def _on_message(self, msg: Any) -> None:
        track, kind = self.track, msg.get_type()
        if kind == "LOCAL_POSITION_NED":
            track.position = (msg.x, msg.y, msg.z)
            if not track.armed and track.highest_m < 1.0:  # on the ground, before the flight
                track.ground_z = msg.z
            height = track.ground_z - msg.z
            track.highest_m = max(track.highest_m, height)
            if track.at_height is None and height > ALTITUDE_M - 0.5:
                track.at_height = (msg.x, msg.y)
            if track.at_height is not None and track.touchdown is None and height < GROUND_M:
                track.touchdown = (msg.x, msg.y)
        elif kind == "HEARTBEAT":
            armed = bool(msg.base_mode & mavutil.mavlink.MAV_MODE_FLAG_SAFETY_ARMED)
            if track.armed and not armed and track.highest_m > ALTITUDE_M - 1:
                track.landed_disarmed = True
            track.armed = armed
        else:
            track.texts.append(msg.text)

    def close(self) -> None:
        self.link.close()



def observer_url(vehicle: sitl.Sitl) -> str:
    """The second link: ArduCopter's SERIAL1 (SERIAL0 + 2), PX4's GCS port (18570 + instance)."""
    address = urlparse(vehicle.connection_string)
    assert address.port is not None
    if vehicle.name == "arducopter":
        return f"tcp:127.0.0.1:{address.port + 2}"
    return f"udpout:127.0.0.1:{18570 + address.port - 14540}"


@contextlib.contextmanager
def uav_tui(vehicle: sitl.Sitl, tmp_path: Path) -> Iterator[subprocess.Popen[str]]:
    """``uav-tui --no-ui`` flying the take-off and ``precland``; stopped (SIGTERM) on leaving."""
    script = tmp_path / "precland.txt"
    script.write_text(f"wait {vehicle.ready_after_s:g}\narm\ntakeoff {ALTITUDE_M:g}\nwait 20\nprecland\nwait 180\n")
    log = (tmp_path / "uav-tui.log").open("w")
    process = subprocess.Popen(
        [sys.executable, "-m", "uav_tui", "--no-ui", "--fc", vehicle.connection_string, "--source", SOURCE,
         "--processor", "precision_land", "--processor-arg", "marker_id=7", "--script", str(script),
         "--runs-dir", str(tmp_path / "runs")],
        cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)}, stdout=log, stderr=subprocess.STDOUT, text=True)
    try:
        yield process
    finally:
        sitl.stop_uav_tui(process)
        log.close()


@pytest.mark.timeout(420)
@pytest.mark.parametrize("launch, params", [
    (sitl.arducopter, {"PLND_ENABLED": 1, "PLND_TYPE": 1}),
    (sitl.px4_sih, {"PLD_FAPPR_ALT": 1.5}),
], ids=["arducopter", "px4_sih"])
def test_precland_lands_on_the_marker_by_the_autopilots_own_position(
        launch: Callable[..., AbstractContextManager[sitl.Sitl]], params: dict[str, float], tmp_path: Path) -> None:
    workdir = tmp_path / "sitl"
    workdir.mkdir()
    with launch(workdir, params) as vehicle, uav_tui(vehicle, tmp_path) as process:
        observer = Observer(observer_url(vehicle))
        try:
            deadline = time.monotonic() + 330
            while not observer.track.landed_disarmed and time.monotonic() < deadline and process.poll() is None:
                time.sleep(0.2)
        finally:
            observer.close()
        track = observer.track
        context = (f"\n--- uav-tui ---\n{(tmp_path / 'uav-tui.log').read_text()[-4000:]}\n--- autopilot texts ---\n"
                   + "\n".join(track.texts[-40:]) + f"\n--- {vehicle.name} log ---\n{vehicle.log_tail()}")
    assert track.landed_disarmed, f"no touchdown and disarm seen (track {track}){context}"
    assert track.at_height is not None and track.touchdown is not None and track.position is not None
    before = math.dist(track.at_height, PAD_NE)
    miss = math.dist(track.touchdown, PAD_NE)
    print(f"{vehicle.name}: {before:.2f} m from the marker at {ALTITUDE_M:g} m, touched down {miss:.3f} m from it "
          f"at {track.touchdown}; disarmed at {track.position} ({math.dist(track.position[:2], PAD_NE):.3f} m)")
    assert before > PAD_NE[0] - 0.5, f"took off {before:.2f} m from the marker: the flight proves nothing"
    assert miss < GOAL_M[vehicle.name], f"touched down {miss:.2f} m from the marker (at {track.touchdown}){context}"
    frames = dataset.load(next((tmp_path / "runs").iterdir())).frames
    assert (frames["landing"] == "sent").sum() > 20, frames["landing"].value_counts()
    modes = set(frames["flight_mode"].dropna())
    assert LANDING_MODE[vehicle.name] in modes and "UNKNOWN" not in modes, modes
