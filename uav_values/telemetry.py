"""Telemetry as every level sees it: the autopilot's newest values, pose samples, and a frame's snapshot.

:class:`Telemetry` is what a flight controller reports (``controllers``), the platform records and interpolates
(``uav_tui``); :class:`Snapshot` is what a processor gets from ``self.tmMgr.snapshot()``: the telemetry at its
frame's capture, with that frame's number and capture time. Every field is typed; None where unknown.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Literal


@dataclass(frozen=True, slots=True)
class PoseSample:
    """One position (``north_m, east_m, down_m``), attitude (``roll, pitch, yaw`` degrees) or gimbal attitude sample
    (``roll, pitch, yaw`` degrees: roll and pitch from the horizon, yaw from the vehicle's nose for ``gimbal``, from
    north for ``gimbal_earth``)."""

    kind: Literal["position", "attitude", "gimbal", "gimbal_earth"]
    t_mono_ns: int
    """When the autopilot measured it, on this computer's ``time.monotonic_ns()`` clock."""
    values: tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class Telemetry:
    """The newest known value of every telemetry field; None where nothing has arrived yet.

    Angles are degrees, positions metres (NED relative to the autopilot's local origin, i.e. home),
    velocities m/s, times nanoseconds. ``t_mono_ns``/``t_wall_ns`` are when the last field changed on
    this computer; ``fc_boot_ms`` is the autopilot's own clock where MAVLink carries it;
    ``fc_clock_offset_ms`` is the autopilot's UTC time (from GPS, in SYSTEM_TIME) minus this
    computer's wall clock, once the autopilot knows the time (a Pi without a network has none right).
    """

    t_mono_ns: int = 0
    t_wall_ns: int = 0
    fc_boot_ms: int | None = None
    fc_clock_offset_ms: int | None = None
    lat_deg: float | None = None
    lon_deg: float | None = None
    abs_alt_m: float | None = None
    rel_alt_m: float | None = None
    rangefinder_m: float | None = None
    """A downward rangefinder's reading (along the vehicle's down axis), None without one or out of its range."""
    terrain_height_m: float | None = None
    """The autopilot's height above the terrain (PX4's ALTITUDE ``bottom_clearance``, ArduPilot's TERRAIN_REPORT
    ``current_height``; see :mod:`controllers.mavsdk.terrain`), None when it reports none."""
    rangefinder_t_ns: int | None = None
    """When the last ``rangefinder_m`` reading was received (monotonic ns; set by the platform)."""
    terrain_t_ns: int | None = None
    """When the last ``terrain_height_m`` reading was received (monotonic ns; set by the platform)."""
    roll_deg: float | None = None
    pitch_deg: float | None = None
    yaw_deg: float | None = None
    north_m: float | None = None
    east_m: float | None = None
    down_m: float | None = None
    vn_ms: float | None = None
    ve_ms: float | None = None
    vd_ms: float | None = None
    battery_v: float | None = None
    battery_pct: float | None = None
    flight_mode: str | None = None
    """MAVSDK's name (HOLD, OFFBOARD...), or the HEARTBEAT's where it has none (:mod:`controllers.flight_modes`)."""
    armed: bool | None = None
    in_air: bool | None = None
    gps_fix: str | None = None
    satellites: int | None = None
    health_ok: bool | None = None
    heartbeat_age_s: float | None = None
    gimbal_roll_deg: float | None = None
    gimbal_pitch_deg: float | None = None
    """The gimbal's attitude where there is one (gimbal protocol v2): roll and pitch from the horizon (pitch
    positive up), yaw from north; the camera on it looks along its forward axis."""
    gimbal_yaw_deg: float | None = None
    link_quality_pct: float | None = None
    """The weakest link signal reported within the last seconds, 0-100 %: the RC receiver's (RC_CHANNELS ``rssi``)
    or a telemetry radio's (RADIO_STATUS), on the device's own scale; None where nothing reports one
    (:mod:`controllers.mavsdk.link_quality`)."""
    link_quality_t_ns: int | None = None
    """When the last ``link_quality_pct`` was received (monotonic ns; set by the platform)."""


TELEMETRY_FIELDS: tuple[str, ...] = tuple(f.name for f in fields(Telemetry))
"""Column order of ``Telemetry`` (and of telemetry.csv)."""
RECEIVE_STAMPS = {"rangefinder_m": "rangefinder_t_ns", "terrain_height_m": "terrain_t_ns",
                  "link_quality_pct": "link_quality_t_ns"}
"""Readings whose receive time the platform keeps (their age decides whether geo-location uses them, and whether the
envelope's link floor may act): field -> the field of its receive time."""


@dataclass(frozen=True, slots=True)
class Snapshot(Telemetry):
    """The telemetry at the capture of the frame being processed, and that frame's number and capture time.

    Telemetry fields as in :class:`Telemetry` (None where unknown: no vehicle, or nothing received before the
    capture; ``heartbeat_age_s`` is the heartbeat's age when the frame was handed over). Outside
    ``photo_processing`` (``catch_cmd``, ``customize_processing``) it is the last frame's.
    """

    frame_seq: int = 0
    """The frame's capture number, 1 for the first frame of the camera (eval: of the sequence); 0 before any."""
    frame_t_ns: int = 0
    """Its capture time, monotonic nanoseconds: the clock to pace by. Live it is ``time.monotonic_ns()`` at capture,
    in a replay the recorded capture time, in eval the frame's time in the sequence (``(frame_seq - 1) / fps``)."""
    frame_t_wall_ns: int = 0
    """The capture's wall-clock time (eval: 0)."""

    @property
    def frame_t_s(self) -> float:
        """``frame_t_ns`` in seconds."""
        return self.frame_t_ns / 1e9
