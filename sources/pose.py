"""The vehicle's pose over time, for the ``sim:`` camera: telemetry samples in, the pose at any instant out.

The platform feeds a :class:`PoseTrack` from the flight controller's telemetry (any autopilot:
LOCAL_POSITION_NED and ATTITUDE stamped on this computer's monotonic clock) and hands it to the
camera as its :class:`PoseProvider`; the camera asks for the pose at each frame's capture time.
"""

from __future__ import annotations

import bisect
import math
import threading
from dataclasses import dataclass
from typing import Protocol

from sources.sim_geometry import Pose

MAX_EXTRAPOLATION_S = 0.05
"""A capture time past the newest sample is extrapolated this far at most; beyond it the pose holds."""

HISTORY = 256
"""Samples kept per series: ~5 s at 50 Hz, far more than any frame's age."""


@dataclass(frozen=True, slots=True)
class PoseAt:
    """The pose at a requested instant and how far it was extrapolated past the newest sample.

    ``extrapolated_s`` is 0 when the instant lies between samples; it may exceed
    :data:`MAX_EXTRAPOLATION_S` (telemetry late or stopped), but the pose itself never moves further.
    """

    pose: Pose
    extrapolated_s: float
    gimbal: tuple[float, float, float] | None = None
    """The gimbal's attitude at that instant (roll, pitch from the horizon; yaw from the vehicle's nose; degrees),
    None without gimbal telemetry."""


class PoseProvider(Protocol):
    """What the ``sim:`` camera needs: the vehicle's pose at ``t_mono_ns`` (``time.monotonic_ns()``).

    Returns None while there is no pose yet. Called on the capture thread.
    """

    def __call__(self, t_mono_ns: int) -> PoseAt | None: ...


class _Series:
    """Timestamped vectors, read back by linear interpolation (``angular`` components wrap at 360)."""

    def __init__(self, angular: tuple[bool, ...], history: int) -> None:
        self.angular, self.history = angular, history
        self.times: list[int] = []
        self.values: list[tuple[float, ...]] = []

    def add(self, t_ns: int, values: tuple[float, ...]) -> None:
        if self.times and t_ns <= self.times[-1]:
            return  # out of order or repeated: the newer sample already counts
        self.times.append(t_ns)
        self.values.append(values)
        if len(self.times) > 2 * self.history:
            del self.times[:-self.history], self.values[:-self.history]

    def at(self, t_ns: int) -> tuple[tuple[float, ...], float]:
        """(values at ``t_ns``, seconds extrapolated past the newest sample)."""
        times, values = self.times, self.values
        lead = max(0.0, (t_ns - times[-1]) / 1e9)
        if len(times) == 1 or t_ns <= times[0]:
            return (values[0] if t_ns <= times[0] else values[-1]), lead
        i = min(bisect.bisect_right(times, t_ns), len(times) - 1)
        t = min(t_ns, times[-1] + int(MAX_EXTRAPOLATION_S * 1e9))
        fraction = (t - times[i - 1]) / (times[i] - times[i - 1])
        return self._blend(values[i - 1], values[i], fraction), lead

    def _blend(self, a: tuple[float, ...], b: tuple[float, ...], fraction: float) -> tuple[float, ...]:
        out = []
        for x, y, angular in zip(a, b, self.angular, strict=True):
            step = (y - x + 180.0) % 360.0 - 180.0 if angular else y - x
            value = x + fraction * step
            out.append((value + 180.0) % 360.0 - 180.0 if angular else value)
        return tuple(out)


class PoseTrack:
    """Position and attitude samples from telemetry; calling it gives the pose at a capture time.

    ``add_position`` / ``add_attitude`` may be called from the event loop while the camera calls
    the track from its capture thread. Samples are interpolated linearly (the shorter way round for
    angles), extrapolated from the last two samples for at most :data:`MAX_EXTRAPOLATION_S`.
    At least the newest ``history`` samples of each kind are kept.
    """

    def __init__(self, history: int = HISTORY) -> None:
        self._lock = threading.Lock()
        self._position = _Series((False, False, False), history)
        self._attitude = _Series((True, True, True), history)
        self._gimbal = _Series((True, True, True), history)

    def add_position(self, t_mono_ns: int, north_m: float, east_m: float, down_m: float) -> None:
        """A local-position sample (m, NED from home) valid at ``t_mono_ns``."""
        if all(math.isfinite(v) for v in (north_m, east_m, down_m)):
            with self._lock:
                self._position.add(t_mono_ns, (north_m, east_m, down_m))

    def add_attitude(self, t_mono_ns: int, roll_deg: float, pitch_deg: float, yaw_deg: float) -> None:
        """An attitude sample (degrees) valid at ``t_mono_ns``."""
        if all(math.isfinite(v) for v in (roll_deg, pitch_deg, yaw_deg)):
            with self._lock:
                self._attitude.add(t_mono_ns, (roll_deg, pitch_deg, yaw_deg))

    def add_gimbal(self, t_mono_ns: int, roll_deg: float, pitch_deg: float, yaw_deg: float, *,
                   earth: bool = False) -> None:
        """A gimbal attitude sample (degrees; roll, pitch from the horizon; yaw from the nose, or from north with
        ``earth``: turned into the nose's frame with the vehicle's heading then, dropped before the first attitude)."""
        if not all(math.isfinite(v) for v in (roll_deg, pitch_deg, yaw_deg)):
            return
        with self._lock:
            if earth:
                if not self._attitude.times:
                    return
                yaw_deg = (yaw_deg - self._attitude.at(t_mono_ns)[0][2] + 180.0) % 360.0 - 180.0
            self._gimbal.add(t_mono_ns, (roll_deg, pitch_deg, yaw_deg))

    def __call__(self, t_mono_ns: int) -> PoseAt | None:
        with self._lock:
            if not self._position.times or not self._attitude.times:
                return None
            (n, e, d), position_lead = self._position.at(t_mono_ns)
            (roll, pitch, yaw), attitude_lead = self._attitude.at(t_mono_ns)
            gimbal = self._gimbal.at(t_mono_ns)[0] if self._gimbal.times else None
        return PoseAt(Pose(n, e, d, roll, pitch, yaw), max(position_lead, attitude_lead),
                      gimbal)  # type: ignore[arg-type]
