"""Issue 47, point 0, on the real autopilots (``sitl``): holds that hold without a pilot, judged by an independent
client.

``uav-tui --no-ui`` takes off to 10 m with the autopilot's own defaults (PX4: ``COM_OBL_RC_ACT`` 0, Position mode,
and no radio) and flies the steering processor's 0.6 m/s vectors under autonomy for 20 s, then is SIGKILLed
mid-vector. A pymavlink client on a second link (ArduCopter's SERIAL1, PX4's GCS port) records the autopilot's
LOCAL_POSITION_NED throughout:

- during the 20 s of autonomy the height stays within 0.5 m of where autonomy engaged;
- after the kill the vehicle stops (judged by displacement: PX4 SIH's velocity estimate wanders), then moves
  less than 1 m in the 5 s that follow, and loses less than 0.5 m of height from the kill to their end.

The same flights on the built-in vehicle: ``test_failsafe_hold.py``.
"""

from __future__ import annotations

import math
import signal
import time
from collections.abc import Callable
from contextlib import AbstractContextManager
from pathlib import Path
from typing import Any

import pytest
from pymavlink import mavutil

from tests import sitl
from tests.core.flight_helpers import start_steering_flight
from tests.core.test_failsafe_hold import AUTONOMY_S, HEIGHT_BAND_M, MOVED_GOAL_M, STILL_WINDOW_S, SUNK_GOAL_M
from tests.core.test_sitl_precland import observer_url
from tests.core.test_sitl_sigkill import wait_line

pytestmark = pytest.mark.sitl

ALTITUDE_M = 10.0
"""The issue's PX4 autonomy climbed from 9.4 m (at 5 m the old code's drift stayed within 0.5 m in one run: -0.46..
+0.23 m; at 10 m it climbed 1.02 m in 20 s)."""
STOPPED_MS = 0.3
"""Stopped: displaced less than this per second over :data:`SPEED_WINDOW_S`."""
SPEED_WINDOW_S = 0.5

Sample = tuple[float, float, float, float]
"""(time.monotonic(), north, east, height above the local origin)."""


class Track:
    """LOCAL_POSITION_NED at 20 Hz and the flight mode, recorded on a second link (:class:`tests.sitl.SecondLink`)."""

    def __init__(self, url: str) -> None:
        self.samples: list[Sample] = []
        self.mode = ""
        self.link = sitl.SecondLink(url, 202, "LOCAL_POSITION_NED", ["LOCAL_POSITION_NED", "HEARTBEAT"],
                                    self._on_message, "failsafe-observer", rate_hz=20.0)

    def _on_message(self, msg: Any) -> None:
        if msg.get_type() == "LOCAL_POSITION_NED":
            self.samples.append((time.monotonic(), msg.x, msg.y, -msg.z))
        else:
            self.mode = mavutil.mode_string_v10(msg)

    def since(self, t: float) -> list[Sample]:
        return [s for s in list(self.samples) if s[0] >= t]

    def close(self) -> None:
        self.link.close()


def stop_time(samples: list[Sample]) -> float | None:
    """The first time from which the vehicle moves less than :data:`STOPPED_MS` over :data:`SPEED_WINDOW_S`."""
    for i, first in enumerate(samples):
        later = next((s for s in samples[i:] if s[0] - first[0] >= SPEED_WINDOW_S), None)
        if later is None:
            return None
        if math.hypot(later[1] - first[1], later[2] - first[2]) / (later[0] - first[0]) < STOPPED_MS:
            return first[0]
    return None


@pytest.mark.timeout(420)
@pytest.mark.parametrize("launch", [sitl.px4_sih, sitl.arducopter], ids=["px4_sih", "arducopter"])
def test_height_held_in_autonomy_and_after_sigkill(launch: Callable[..., AbstractContextManager[sitl.Sitl]],
                                                   tmp_path: Path) -> None:
    workdir = tmp_path / "sitl"
    workdir.mkdir()
    with launch(workdir) as vehicle:
        script = (f"wait {vehicle.ready_after_s:g}\narm\ntakeoff {ALTITUDE_M:g}\nwait 12\nf 1\nautonomy on\n"
                  "wait 180\n")
        track = Track(observer_url(vehicle))
        process = start_steering_flight(tmp_path, vehicle.connection_string, script)
        try:
            seen = wait_line(process, "autonomy ON", vehicle.ready_after_s + 90)
            seen += wait_line(process, "s (executed)", 20)
            engaged = time.monotonic()
            time.sleep(AUTONOMY_S)
            autonomy = track.since(engaged)
            process.send_signal(signal.SIGKILL)
            killed = time.monotonic()
            process.communicate(timeout=10)
            deadline = killed + 20
            while (stopped := stop_time(track.since(killed))) is None or time.monotonic() < stopped + STILL_WINDOW_S:
                assert time.monotonic() < deadline, f"not stopped 20 s after the kill (in {track.mode})"
                time.sleep(0.2)
            after = track.since(killed)
            mode = track.mode
        finally:
            process.kill()
            process.communicate()
            track.close()
    heights = [s[3] - autonomy[0][3] for s in autonomy]
    flown = math.hypot(autonomy[-1][1] - autonomy[0][1], autonomy[-1][2] - autonomy[0][2])
    at_kill = after[0]
    still = [s for s in after if stopped <= s[0] <= stopped + STILL_WINDOW_S]
    moved = max(math.hypot(s[1] - still[0][1], s[2] - still[0][2]) for s in still)
    sunk = at_kill[3] - min(s[3] for s in after if s[0] <= stopped + STILL_WINDOW_S)
    print(f"{vehicle.name}: {AUTONOMY_S:g} s of autonomy from {autonomy[0][3]:.2f} m flew {flown:.1f} m, height "
          f"{min(heights):+.2f}..{max(heights):+.2f} m; after SIGKILL at {at_kill[3]:.2f} m: stopped after "
          f"{stopped - killed:.2f} s, then moved {moved:.2f} m in {STILL_WINDOW_S:g} s, sank {sunk:.2f} m, in {mode}")
    output = "".join(seen)
    assert flown > 6.0, f"the vectors did not fly ({flown:.1f} m)\n{output[-3000:]}"
    assert max(map(abs, heights)) < HEIGHT_BAND_M
    assert moved < MOVED_GOAL_M and sunk < SUNK_GOAL_M
    if vehicle.name == "px4":
        assert "set COM_OBL_RC_ACT 0 -> 5" in output
