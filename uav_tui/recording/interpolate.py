"""Telemetry at an arbitrary instant: linear for continuous values, angles unwrapped, nearest for discrete.

Telemetry arrives as a stream of snapshots (:class:`controllers.base.Telemetry`), one per partial
update, each stamped with the monotonic time it was received. A snapshot carries every field, but
only the fields of the update that produced it are new; the others repeat older values. So each
continuous field keeps its own series of the instants where its value changed, and is interpolated
between those, not between snapshots where it only repeated itself. Discrete fields (mode, armed,
fix ...) take the value of the snapshot nearest in time.
"""

from __future__ import annotations

import bisect
import math
from typing import Any

from controllers.base import RECEIVE_STAMPS, Telemetry

CONTINUOUS: tuple[str, ...] = (
    "fc_boot_ms", "lat_deg", "lon_deg", "abs_alt_m", "rel_alt_m", "roll_deg", "pitch_deg", "yaw_deg",
    "north_m", "east_m", "down_m", "vn_ms", "ve_ms", "vd_ms", "battery_v", "battery_pct", "rangefinder_m",
    "gimbal_roll_deg", "gimbal_pitch_deg", "gimbal_yaw_deg",
    "terrain_height_m",
)
"""Fields interpolated linearly."""

GAPS = frozenset({"rangefinder_m", "terrain_height_m"})
"""Continuous fields whose None after a value is news (a rangefinder out of its range): kept as a gap, so no
line is drawn across it and an instant next to it has no value."""

ANGLES = frozenset({"roll_deg", "pitch_deg", "yaw_deg", "gimbal_roll_deg", "gimbal_pitch_deg", "gimbal_yaw_deg"})
"""Continuous fields in degrees that wrap at +-180: interpolated the short way round."""

DISCRETE: tuple[str, ...] = ("flight_mode", "armed", "in_air", "gps_fix", "satellites", "health_ok")
"""Fields taken from the nearest snapshot."""

STAMPS: tuple[str, ...] = tuple(RECEIVE_STAMPS.values())
"""Receive times of readings: taken from the newest snapshot at or before the instant (how old the reading
interpolated there is, at the latest), so an instant past a sensor that stopped sees its age."""

FIELDS: tuple[str, ...] = CONTINUOUS + DISCRETE + STAMPS
"""Every field a frame row carries, in column order."""

STATIC_NS = 300_000_000
"""A field unchanged for this long, while other telemetry keeps arriving, is taken as constant: until the snapshot
before its next change, not a line from its last change to the next one."""

KEEP_NS = 5_000_000_000
"""History older than this (behind the newest sample) is forgotten."""


class TelemetryHistory:
    """The last few seconds of telemetry, queryable at any instant. Used by one thread only."""

    def __init__(self, keep_ns: int = KEEP_NS) -> None:
        self.keep_ns = keep_ns
        self._times: list[int] = []
        self._snapshots: list[Telemetry] = []
        self._series: dict[str, tuple[list[int], list[float]]] = {name: ([], []) for name in CONTINUOUS}
        self._late: dict[str, int] = {}
        """Continuous fields first reported after the first snapshot, and when: unknown before that (a battery
        message 0.2 s after the position), whenever the row is written, so a replay computes the same row."""

    def __len__(self) -> int:
        return len(self._times)

    @property
    def newest_ns(self) -> int | None:
        """Receive time of the newest sample (None before the first)."""
        return self._times[-1] if self._times else None

    def add(self, sample: Telemetry, t_ns: int) -> None:
        """Append a snapshot received at ``t_ns`` (monotonic, not older than the previous one)."""
        previous = self._snapshots[-1] if self._snapshots else None
        before = self._times[-1] if previous is not None else t_ns  # the snapshot before this one
        self._times.append(t_ns)
        self._snapshots.append(sample)
        for name, (times, values) in self._series.items():
            given = getattr(sample, name)
            gap = given is None and name in GAPS and values and not math.isnan(values[-1])
            value = math.nan if gap else given
            if value is not None and (previous is None or getattr(previous, name) != given or not times):
                if previous is not None and not times and name not in self._late:
                    self._late[name] = t_ns
                if times and before - times[-1] >= STATIC_NS and before < t_ns:
                    times.append(before)  # constant (see covers) until the snapshot before this change
                    values.append(values[-1])
                times.append(t_ns)
                values.append(float(value))
        self._trim(t_ns - self.keep_ns)

    def covers(self, t_ns: int) -> bool:
        """True when telemetry after ``t_ns`` arrived and every continuous field changed again after it.

        Until then a later sample could still refine the interpolation at ``t_ns``. A field that has
        not changed for :data:`STATIC_NS` counts as constant (a battery percentage, a parked vehicle).
        """
        newest = self.newest_ns
        if newest is None or newest < t_ns:
            return False
        return all(not times or times[-1] >= t_ns or newest - times[-1] >= STATIC_NS
                   for times, _ in self._series.values())

    def at(self, t_ns: int) -> tuple[dict[str, Any], str]:
        """Every field of :data:`FIELDS` at ``t_ns`` and how it was obtained.

        Returns:
            ``(values, how)``: values are None where nothing is known (a field first reported after the first
            snapshot is not known before its first sample, so a row does not depend on when it was written);
            ``how`` is ``interpolated`` (samples on both sides of every field: :meth:`covers`), ``held`` (some
            field has only older
            samples: its newest value), ``before`` (only newer samples: the oldest values) or ``none``
            (no telemetry). :meth:`extrapolated_ns` says how far ``held`` and ``before`` reach.
        """
        if not self._times:
            return dict.fromkeys(FIELDS), "none"
        values: dict[str, Any] = {name: None if t_ns < self._late.get(name, t_ns) else
                                  _interpolate(*self._series[name], t_ns, name in ANGLES) for name in CONTINUOUS}
        values.update({name: None for name in GAPS if values[name] is not None and math.isnan(values[name])})
        if values["fc_boot_ms"] is not None:
            values["fc_boot_ms"] = round(values["fc_boot_ms"])
        nearest = self._snapshots[_nearest(self._times, t_ns)]
        values.update({name: getattr(nearest, name) for name in DISCRETE})
        before = self._snapshots[max(bisect.bisect_right(self._times, t_ns) - 1, 0)]
        values.update({name: getattr(before, name) for name in STAMPS})
        if t_ns < self._times[0]:
            how = "before"
        elif self.covers(t_ns):
            how = "interpolated"
        else:
            how = "held"
        return values, how

    def extrapolated_ns(self, t_ns: int) -> int | None:
        """How far :meth:`at` reaches past the samples at ``t_ns``: 0 where they bracket it (:meth:`covers`).

        Before the first sample, how long before it; else the longest a changing field is held past its newest
        value (a field constant for :data:`STATIC_NS` past the newest sample). None without telemetry.
        """
        if not self._times:
            return None
        if t_ns < self._times[0]:
            return self._times[0] - t_ns
        newest = self._times[-1]
        held = [t_ns - times[-1] for times, _ in self._series.values()
                if times and times[-1] < t_ns and newest - times[-1] < STATIC_NS]
        return max(0, t_ns - newest, *held)

    def _trim(self, oldest_ns: int) -> None:
        cut = bisect.bisect_left(self._times, oldest_ns)
        if cut > 1:  # always keep one sample older than the window
            del self._times[:cut - 1], self._snapshots[:cut - 1]
        for times, values in self._series.values():
            cut = bisect.bisect_left(times, oldest_ns)
            if cut > 1:
                del times[:cut - 1], values[:cut - 1]


def _interpolate(times: list[int], values: list[float], t_ns: int, angle: bool) -> float | None:
    if not times:
        return None
    right = bisect.bisect_left(times, t_ns)
    if right == 0:
        return values[0]
    if right == len(times):
        return values[-1]
    t0, t1, v0, v1 = times[right - 1], times[right], values[right - 1], values[right]
    if t1 == t0:
        return v1
    fraction = (t_ns - t0) / (t1 - t0)
    if not angle:
        return v0 + fraction * (v1 - v0)
    step = (v1 - v0 + 180.0) % 360.0 - 180.0  # the short way round
    low = 0.0 if min(v0, v1) >= 0.0 and max(v0, v1) > 180.0 else -180.0  # keep the autopilot's convention
    return (v0 + fraction * step - low) % 360.0 + low


def _nearest(times: list[int], t_ns: int) -> int:
    right = bisect.bisect_left(times, t_ns)
    if right == 0:
        return 0
    if right == len(times):
        return len(times) - 1
    return right if times[right] - t_ns < t_ns - times[right - 1] else right - 1
