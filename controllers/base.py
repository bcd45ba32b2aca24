"""The flight-controller contract and the telemetry value type it produces."""

from __future__ import annotations

from collections.abc import AsyncIterator
from dataclasses import dataclass, fields
from typing import Any, Literal, Protocol, runtime_checkable


@dataclass(frozen=True, slots=True)
class PoseSample:
    """One position (``north_m, east_m, down_m``) or attitude (``roll, pitch, yaw`` degrees) sample."""

    kind: Literal["position", "attitude"]
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
    armed: bool | None = None
    in_air: bool | None = None
    gps_fix: str | None = None
    satellites: int | None = None
    health_ok: bool | None = None
    heartbeat_age_s: float | None = None


TELEMETRY_FIELDS: tuple[str, ...] = tuple(f.name for f in fields(Telemetry))
"""Column order of ``Telemetry`` (and of telemetry.csv)."""


@runtime_checkable
class FlightController(Protocol):
    """What the platform needs from a flight controller.

    Every command either completes or raises a :class:`uav_tui.errors.ControllerError` carrying the
    autopilot's answer; none is a silent no-op.

    ``set_fly_vector`` returns as soon as the vector is running; the controller streams the
    body-frame velocity setpoint at >= 10 Hz for ``t`` seconds, then sends zero and puts the vehicle
    in a holding mode itself. A new vector replaces the running one.

    Optional: ``pose_samples()``, an async iterator of timestamped position and attitude samples
    (:class:`controllers.mavsdk_pose.PoseSample`), which the ``sim:`` camera is drawn from; ``own_modes``,
    the flight modes its vectors and holds leave the vehicle in (default HOLD and OFFBOARD; any other is
    a pilot's, a mission's or a failsafe's, which autonomy and the hold at exit leave alone);
    ``send_landing_target(fix)``, LANDING_TARGET for a :class:`controllers.landing_target.LandingTargetFix`,
    converted for the autopilot and stamped with the capture time on its clock.
    """

    description: str
    """Human-readable: autopilot kind and connection string."""

    async def connect(self, system_address: str) -> None: ...
    async def close(self) -> None: ...
    async def arm(self) -> None: ...
    async def disarm(self) -> None: ...
    async def takeoff(self, altitude_m: float | None = None) -> None: ...
    async def land(self) -> None: ...
    async def set_fly_vector(self, vx: float, vy: float, t: float) -> None: ...
    async def do_orbit(self, radius_m: float, velocity_ms: float) -> None: ...
    async def return_to_home(self) -> None: ...
    async def hold(self) -> None: ...

    @property
    def vector_active(self) -> bool:
        """True while a vector's setpoints are being streamed."""
        ...

    @property
    def last_vector_end(self) -> str:
        """How the last vector ended: ``completed``, ``stopped``, ``vehicle left offboard (MODE)``, ``failed: ...``."""
        ...

    def heartbeat_age_s(self) -> float:
        """Seconds since the last heartbeat from the autopilot (inf before the first)."""
        ...

    def telemetry(self) -> AsyncIterator[dict[str, Any]]:
        """Partial telemetry updates keyed by :class:`Telemetry` field names, as they arrive."""
        ...
