"""Issue 49's envelope on real autopilots (``sitl``): a processor that only ever says "forward at full speed".

``uav-tui --no-ui`` takes off to 5 m, switches autonomy on with :data:`RADIUS_M` as the envelope's radius and the
default ``max_speed`` (1 m/s), leaves it on for :data:`AUTONOMY_S`, then lands. An independent pymavlink client on
a second link (ArduCopter's SERIAL1, PX4's GCS port) reads the autopilot's GLOBAL_POSITION_INT all through the
flight: the judge is its horizontal distance from where the vehicle stood before arming (the local origin the
envelope's radius is measured from), which must stay within the radius + :data:`MARGIN_M`.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import time
from collections.abc import Callable
from contextlib import AbstractContextManager
from pathlib import Path
from typing import Any

import pytest
from pymavlink import mavutil

from tests import sitl
from tests.core.test_sitl_precland import observer_url

pytestmark = pytest.mark.sitl

ROOT = Path(__file__).resolve().parents[2]
RADIUS_M = 8.0
MARGIN_M = 1.5
"""The issue's bound beyond the radius on a real SITL. Measured (one run each, load average 5-7 on 2 cores):
ArduCopter 0.15 m beyond, PX4 SIH 0.71 m."""
AUTONOMY_S = 30.0
"""Autonomy on this long: 8 s to the radius at 1 m/s, the rest pushing against it."""
EARTH_RADIUS_M = 6_371_000.0

FORWARD_PROCESSOR = '''
class Forward:
    """Test processor: forward at ten times any sane speed, on every frame."""

    def __init__(self):
        self.tmMgr = None

    def photo_processing(self, frame):
        pass

    def customize_processing(self, id):
        pass

    def catch_cmd(self, roi):
        pass

    def getPreparedVector(self):
        return (10.0, 0.0, 2.0)
'''


class Observer:
    """The autopilot's GLOBAL_POSITION_INT and HEARTBEAT, read on a second link (:class:`tests.sitl.SecondLink`)."""

    def __init__(self, url: str) -> None:
        self.home: tuple[float, float] | None = None
        """(lat, lon) of the last position before arming."""
        self.farthest_m = 0.0
        """The largest horizontal distance from :attr:`home` while armed."""
        self.armed = False
        self.flown_and_disarmed = False
        self.link = sitl.SecondLink(url, 203, "GLOBAL_POSITION_INT", ["GLOBAL_POSITION_INT", "HEARTBEAT"],
                                    self._on_message, "envelope-observer")

    def _on_message(self, msg: Any) -> None:
        if msg.get_type() == "HEARTBEAT":
            armed = bool(msg.base_mode & mavutil.mavlink.MAV_MODE_FLAG_SAFETY_ARMED)
            self.flown_and_disarmed |= self.armed and not armed and self.farthest_m > 1.0
            self.armed = armed
            return
        position = (msg.lat / 1e7, msg.lon / 1e7)
        if position == (0.0, 0.0):
            return  # ArduCopter before its first fix
        if not self.armed and self.farthest_m == 0.0:
            self.home = position
        elif self.home is not None:
            self.farthest_m = max(self.farthest_m, distance_m(self.home, position))

    def close(self) -> None:
        self.link.close()


def distance_m(a: tuple[float, float], b: tuple[float, float]) -> float:
    """Horizontal metres between two (lat, lon) points (flat earth: they are metres apart)."""
    north = math.radians(b[0] - a[0]) * EARTH_RADIUS_M
    east = math.radians(b[1] - a[1]) * EARTH_RADIUS_M * math.cos(math.radians(a[0]))
    return math.hypot(north, east)


@pytest.mark.timeout(480)
@pytest.mark.parametrize("launch", [sitl.arducopter, sitl.px4_sih], ids=["arducopter", "px4_sih"])
def test_forward_at_full_speed_stays_within_the_radius_by_an_independent_link(
        launch: Callable[[Path], AbstractContextManager[sitl.Sitl]], tmp_path: Path) -> None:
    workdir = tmp_path / "sitl"
    workdir.mkdir()
    (tmp_path / "forward.py").write_text(FORWARD_PROCESSOR)
    log_path = tmp_path / "uav-tui.log"
    with launch(workdir) as vehicle:
        (tmp_path / "flight.txt").write_text(f"wait {vehicle.ready_after_s:g}\narm\ntakeoff 5\nwait 15\nautonomy on\n"
                                             f"wait {AUTONOMY_S:g}\nautonomy off\nland\nwait 60\n")
        observer = Observer(observer_url(vehicle))
        with log_path.open("w") as log:
            process = subprocess.Popen(
                [sys.executable, "-m", "uav_tui", "--no-ui", "--fc", vehicle.connection_string,
                 "--source", "synthetic:?width=160&height=120", "--processor", "forward.py:Forward",
                 "--script", "flight.txt", "--no-record", "--radius-m", f"{RADIUS_M:g}"],
                cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)}, stdout=log, stderr=subprocess.STDOUT,
                text=True)
            try:
                deadline = time.monotonic() + 360
                while not observer.flown_and_disarmed and time.monotonic() < deadline and process.poll() is None:
                    time.sleep(0.2)
            finally:
                observer.close()
                sitl.stop_uav_tui(process)
        context = f"\n--- uav-tui ---\n{log_path.read_text()[-4000:]}\n--- {vehicle.name} log ---\n{vehicle.log_tail()}"
    beyond = observer.farthest_m - RADIUS_M
    print(f"{vehicle.name}: farthest {observer.farthest_m:.2f} m from home, {beyond:+.2f} m beyond the "
          f"{RADIUS_M:g} m radius")
    assert observer.flown_and_disarmed, f"no flight and landing seen (farthest {observer.farthest_m:.2f} m){context}"
    assert observer.farthest_m > RADIUS_M - 2.0, f"reached only {observer.farthest_m:.2f} m: proves nothing{context}"
    assert beyond <= MARGIN_M, f"went {beyond:.2f} m beyond the {RADIUS_M:g} m radius{context}"
