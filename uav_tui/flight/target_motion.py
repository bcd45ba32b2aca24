"""The tracked target's ground velocity and heading, from its geo-located positions on the frame clock.

Each processed frame whose ``box`` was located adds its position at the frame's capture time. The velocity is the
slope of a least-squares line through the positions of the last :data:`WINDOW_S` (north and east apart): a fit
over ~30 frames averages out the frame-to-frame jitter of the box and of the attitude (a difference of two
consecutive positions 1/15 s apart would multiply a 0.1 m jitter into 1.5 m/s), at the price of reporting the mean
velocity of the last two seconds: about one second late on a target that turns or brakes. Its 1-sigma accuracy is
from the fit's residuals. The heading is the direction of that velocity, known only while the target moves clearly
(a parked car has none). All NaN without enough positions: fewer than :data:`MIN_FIXES`, spanning less than
:data:`MIN_SPAN_S`, or the newest older than :data:`GAP_S` (a target lost for a second may be another one when
it is found again: its track starts anew).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

from uav_tui.flight.geolocate import EARTH_RADIUS_M, OK, GeoFix

WINDOW_S = 2.0
"""Positions used for the fit: those of the last two seconds before the newest."""

MIN_FIXES = 5
MIN_SPAN_S = 0.5
"""At least this many positions over at least this long for a velocity."""

GAP_S = 1.0
"""A target not located for this long starts a new track (and has no velocity until it has enough positions)."""

MIN_HEADING_SPEED_MS = 0.3
"""Below this speed (or below twice its accuracy) a target has no heading: walking pace is 1.4 m/s."""

NAN = float("nan")


@dataclass(frozen=True, slots=True)
class Motion:
    """Ground velocity (m/s, north and east), its 1-sigma accuracy, heading (radians from north, clockwise, 0..2 pi)
    and its accuracy; NaN where unknown."""

    vel_n: float = NAN
    vel_e: float = NAN
    vel_acc: float = NAN
    heading_rad: float = NAN
    heading_acc_rad: float = NAN


class TargetMotion:
    """The positions of the tracked target over the last :data:`WINDOW_S`, and its velocity from them."""

    def __init__(self) -> None:
        self._fixes: deque[tuple[int, float, float]] = deque()
        """(capture monotonic ns, north m, east m from the track's first position)."""
        self._origin: tuple[float, float] = (0.0, 0.0)

    def reset(self) -> None:
        """Forget the track (another target was selected)."""
        self._fixes.clear()

    def add(self, t_ns: int, fix: GeoFix | None) -> None:
        """The target's position in the frame captured at ``t_ns`` (monotonic); one without a position is skipped."""
        if fix is None or fix.status != OK or fix.lat_deg is None or fix.lon_deg is None:
            return
        if self._fixes and not 0 <= t_ns - self._fixes[-1][0] <= GAP_S * 1e9:
            self._fixes.clear()  # lost for a while (or the clock went back: a camera switch): a new track
        if not self._fixes:
            self._origin = (fix.lat_deg, fix.lon_deg)
        lat0, lon0 = self._origin
        north = math.radians(fix.lat_deg - lat0) * EARTH_RADIUS_M
        east = math.radians(fix.lon_deg - lon0) * EARTH_RADIUS_M * math.cos(math.radians(lat0))
        self._fixes.append((t_ns, north, east))
        while t_ns - self._fixes[0][0] > WINDOW_S * 1e9:
            self._fixes.popleft()

    def motion(self, now_ns: int) -> Motion:
        """The velocity and heading at ``now_ns`` (monotonic), NaN without enough recent positions."""
        fixes = self._fixes
        if len(fixes) < MIN_FIXES or now_ns - fixes[-1][0] > GAP_S * 1e9 \
                or fixes[-1][0] - fixes[0][0] < MIN_SPAN_S * 1e9:
            return Motion()
        times = [(t - fixes[0][0]) / 1e9 for t, _, _ in fixes]
        mean_t = sum(times) / len(times)
        spread = sum((t - mean_t) ** 2 for t in times)
        slopes, variances = [], []
        for axis in (1, 2):
            values = [fix[axis] for fix in fixes]
            mean_v = sum(values) / len(values)
            slope = sum((t - mean_t) * (v - mean_v) for t, v in zip(times, values, strict=True)) / spread
            residual = sum((v - mean_v - slope * (t - mean_t)) ** 2 for t, v in zip(times, values, strict=True))
            slopes.append(slope)
            variances.append(residual / (len(values) - 2) / spread)
        vel_n, vel_e = slopes
        vel_acc = math.sqrt(sum(variances))
        speed = math.hypot(vel_n, vel_e)
        if speed < max(MIN_HEADING_SPEED_MS, 2 * vel_acc):
            return Motion(vel_n, vel_e, vel_acc)
        return Motion(vel_n, vel_e, vel_acc, math.atan2(vel_e, vel_n) % math.tau, math.atan2(vel_acc, speed))
