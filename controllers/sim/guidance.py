"""Flight modes of the simulated vehicle: each turns the vehicle state into a velocity demand.

Modes follow PX4's behaviour: HOLD brakes to a stop and keeps that position, TAKEOFF climbs to the
takeoff altitude and then holds, LAND descends and disarms on touchdown, PRECLAND (PX4's Precision Land)
lands on the pad LANDING_TARGET gives, RTL climbs to the RTL altitude, flies home and lands, ORBIT circles a
centre, OFFBOARD follows the newest setpoint.
Two are ArduCopter's (the ``ardupilot`` dialect): GUIDED follows the newest setpoint and otherwise
holds its stopping point, LOITER holds its position but climbs or sinks with the RC throttle stick.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from controllers.sim.physics import Multicopter


class Mode(StrEnum):
    """Flight modes; the MAVLink layer maps them onto PX4 custom modes."""

    MANUAL = "MANUAL"
    POSCTL = "POSCTL"
    HOLD = "HOLD"
    TAKEOFF = "TAKEOFF"
    LAND = "LAND"
    PRECLAND = "PRECLAND"
    RTL = "RTL"
    OFFBOARD = "OFFBOARD"
    ORBIT = "ORBIT"
    GUIDED = "GUIDED"
    LOITER = "LOITER"


@dataclass(frozen=True, slots=True)
class OffboardSetpoint:
    """One offboard setpoint. None fields are ignored (the type_mask said so).

    ``velocity`` is NED, or forward/right/down rotated by the current yaw when ``body`` is True.
    ``position`` is local NED metres. ``yaw`` radians, ``yaw_rate`` rad/s.
    """

    velocity: tuple[float, float, float] | None = None
    body: bool = False
    position: tuple[float, float, float] | None = None
    yaw: float | None = None
    yaw_rate: float | None = None


@dataclass(frozen=True, slots=True)
class Orbit:
    """Circle ``radius`` m around (north, east) at ``down``, ``speed`` m/s (>0 clockwise from above)."""

    north: float
    east: float
    down: float
    radius: float
    speed: float


@dataclass(slots=True)
class ThrottleStick:
    """An RC throttle stick read the way ArduCopter reads it (``Copter::get_pilot_desired_climb_rate``).

    ArduCopter SITL's default RC input holds the throttle at 1000 (its minimum); a transmitter left at
    idle does the same. Attributes are ArduCopter's parameters in SI units.
    """

    pwm: int = 1000
    speed_up_ms: float = 2.5
    """PILOT_SPD_UP."""
    speed_dn_ms: float = 0.0
    """PILOT_SPD_DN; 0 means PILOT_SPD_UP."""
    deadzone: int = 100
    """THR_DZ, in the 0..1000 throttle range around mid-stick (500)."""

    def climb_rate(self) -> float:
        """The climb rate (m/s, up positive) the stick asks for in LOITER."""
        throttle = min(max(self.pwm - 1000, 0), 1000)
        bottom, top = 500 - self.deadzone, 500 + self.deadzone
        if throttle < bottom:
            return (self.speed_dn_ms or self.speed_up_ms) * (throttle - bottom) / bottom
        if throttle > top:
            return self.speed_up_ms * (throttle - top) / (1000 - top)
        return 0.0


OFFBOARD_LOSS_ACTIONS = {0: "position_mode", 3: "rtl", 4: "land", 5: "hold"}
"""PX4's COM_OBL_RC_ACT values the simulator honours -> :class:`Guidance` method: 0 Position mode (POSCTL: held by
a pilot's centred sticks with a radio, sinking without one), 3 Return, 4 Land, 5 Hold. PX4's others (Altitude,
Manual, Terminate, Disarm) need a pilot's sticks or end in a crash, and are not simulated."""

UNPILOTED_SINK_MS = 0.55
"""How fast PX4 v1.16 SITL sank in Position mode with no radio after an offboard loss (4.9 m -> 0.45 m in 8 s)."""

Demand = tuple[np.ndarray, float | None, float | None]
"""Velocity demand (NED m/s), yaw goal (rad) or None, yaw rate (rad/s) or None."""


class Guidance:
    """The mode state machine and per-mode velocity demand of one :class:`Multicopter`."""

    def __init__(self, vehicle: Multicopter) -> None:
        self.v = vehicle
        self.mode = Mode.HOLD
        self.target = np.zeros(3)
        self.target_speed: float | None = None
        self.orbit_params: Orbit | None = None
        self.setpoint: OffboardSetpoint | None = None
        self.rtl_phase = "climb"
        self._yaw_goal: float | None = None
        self.stick: ThrottleStick | None = None
        """The RC throttle (ArduCopter dialect); None: no RC, as the PX4 dialect is flown."""
        self.radio = False
        """A radio connected and read (PX4 dialect, ``--radio``): a pilot's centred sticks hold POSCTL."""
        self.unpiloted = False
        """In POSCTL as an offboard-loss fallback with no radio: nobody holds the sticks, it sinks."""
        self.hold_mode = Mode.HOLD
        """What a finished takeoff holds in: PX4 switches to HOLD, ArduCopter stays in GUIDED."""
        self.pad: Callable[[], np.ndarray | None] | None = None
        """The landing pad's (north, east) from precision landing now, or None
        (:mod:`controllers.sim.landing_target_reader`)."""
        self.precision_modes = frozenset({Mode.PRECLAND})
        """The modes that land on :attr:`pad`: PX4's Precision Land; ArduCopter's LAND (with PLND_ENABLED)."""

    # ------------------------------------------------------------ transitions
    def _enter(self, mode: Mode) -> None:
        self.mode = mode
        self.unpiloted = False
        self._yaw_goal = self.v.yaw

    def _stopping_point(self) -> np.ndarray:
        v, a = self.v.vel, self.v.cfg.max_accel_ms2
        point = self.v.pos.copy()
        point[:2] += v[:2] * np.hypot(v[0], v[1]) / (2.0 * a)
        if not self.v.in_air:
            point[2] = 0.0
        return point

    def hold(self, mode: Mode = Mode.HOLD) -> None:
        """Brake and keep the stopping point (also used for POSCTL/MANUAL without sticks)."""
        self._enter(mode)
        self.target = self._stopping_point()
        self.target_speed = None

    def position_mode(self) -> None:
        """PX4's Position mode as the offboard-loss action: the pilot's sticks hold it, or nobody's sink it."""
        self.hold(Mode.POSCTL)
        self.unpiloted = not self.radio

    def guided(self) -> None:
        """ArduCopter GUIDED without a target: brake and keep the stopping point (``ModeGuided::init``)."""
        self.hold(Mode.GUIDED)
        self.setpoint = None

    def follow(self, setpoint: OffboardSetpoint) -> None:
        """A GUIDED target (velocity or position); it replaces a take-off under way, as in ArduCopter."""
        if self.mode != Mode.GUIDED:
            self._enter(Mode.GUIDED)
            self.target = self.v.pos.copy()
        self.setpoint = setpoint

    def loiter(self) -> None:
        """ArduCopter LOITER: hold the stopping point; the throttle stick moves the altitude."""
        self.hold(Mode.LOITER)

    def goto(self, north: float, east: float, down: float, speed: float | None = None) -> None:
        """Fly to a local point and hold there (DO_REPOSITION); shows as HOLD like PX4."""
        self._enter(Mode.HOLD)
        self.target = np.array([north, east, down], dtype=float)
        self.target_speed = speed

    def takeoff(self, altitude_m: float) -> None:
        self._enter(Mode.TAKEOFF)
        self.target = np.array([self.v.pos[0], self.v.pos[1], -altitude_m])

    def land(self, mode: Mode = Mode.LAND) -> None:
        """LAND, or PRECLAND (PX4's Precision Land)."""
        self._enter(mode)
        self.target = self._stopping_point()

    def rtl(self) -> None:
        self._enter(Mode.RTL)
        self.rtl_phase = "climb"
        self.target = self._stopping_point()

    def orbit(self, orbit: Orbit) -> None:
        self._enter(Mode.ORBIT)
        self.orbit_params = orbit

    def offboard(self, setpoint: OffboardSetpoint) -> None:
        if self.mode != Mode.OFFBOARD:
            self._enter(Mode.OFFBOARD)
            self.target = self.v.pos.copy()
        self.setpoint = setpoint

    def on_touchdown(self) -> None:
        if self.mode in (Mode.HOLD, Mode.POSCTL, Mode.MANUAL, Mode.ORBIT, Mode.GUIDED, Mode.LOITER):
            self.target = self.v.pos.copy()

    # ----------------------------------------------------------------- demand
    def demand(self) -> Demand:
        """The velocity the current mode asks for now."""
        handler = {
            Mode.TAKEOFF: self._takeoff,
            Mode.LAND: self._land,
            Mode.PRECLAND: self._land,
            Mode.RTL: self._rtl,
            Mode.ORBIT: self._orbit,
            Mode.OFFBOARD: self._offboard,
            Mode.GUIDED: self._guided,
            Mode.LOITER: self._loiter,
            Mode.POSCTL: self._posctl,
        }.get(self.mode, self._hold)
        return handler()

    def _toward(self, target: np.ndarray, xy_speed: float, z_up: float, z_down: float) -> np.ndarray:
        """P position control: velocity toward ``target`` within the speed limits."""
        cfg = self.v.cfg
        err = target - self.v.pos
        vel = cfg.position_gain * err
        h = float(np.hypot(vel[0], vel[1]))
        dist = float(np.hypot(err[0], err[1]))
        limit = min(xy_speed, math.sqrt(2.0 * 0.5 * cfg.max_accel_ms2 * dist) if dist > 0 else 0.0)
        if h > limit:
            vel[:2] *= limit / h
        vel[2] = float(np.clip(vel[2], -z_up, z_down))
        return vel

    def _hold(self) -> Demand:
        cfg = self.v.cfg
        speed = self.target_speed or cfg.cruise_speed_ms
        vel = self._toward(self.target, speed, cfg.takeoff_speed_ms * 2, cfg.fast_descent_ms)
        return vel, self._yaw_goal, None

    def _guided(self) -> Demand:
        return self._hold() if self.setpoint is None else self._offboard()

    def _loiter(self) -> Demand:
        return self._climbing(self.stick.climb_rate() if self.stick is not None else 0.0)

    def _posctl(self) -> Demand:
        return self._climbing(-UNPILOTED_SINK_MS if self.unpiloted else 0.0)

    def _climbing(self, rate: float) -> Demand:
        """Hold the horizontal stopping point while climbing at ``rate`` (m/s, up positive; 0: hold the height)."""
        if rate:  # the altitude target follows the stick: where the vehicle would stop
            vz = float(self.v.vel[2])
            self.target[2] = self.v.pos[2] + vz * abs(vz) / (2.0 * self.v.cfg.max_accel_ms2)
        vel, yaw, _ = self._hold()
        if rate:
            vel[2] = -rate
        return vel, yaw, None

    def _takeoff(self) -> Demand:
        cfg = self.v.cfg
        vel = self._toward(self.target, cfg.cruise_speed_ms, cfg.takeoff_speed_ms, cfg.fast_descent_ms)
        if abs(self.v.pos[2] - self.target[2]) < 0.1:
            goal = self.target
            self.hold(self.hold_mode)  # PX4 switches to HOLD at the takeoff altitude, ArduCopter stays GUIDED
            self.setpoint = None
            self.target = goal
        return vel, self._yaw_goal, None

    def _descent_speed(self) -> float:
        cfg = self.v.cfg
        return cfg.fast_descent_ms if self.v.altitude > cfg.land_alt1_m else cfg.land_speed_ms

    def _land(self) -> Demand:
        pad = self.pad() if self.pad is not None and self.mode in self.precision_modes else None
        if pad is not None:  # precision landing: over the newest estimate of the pad (kept once it goes stale)
            self.target[:2] = pad
        vel = self._toward(self.target, self.v.cfg.cruise_speed_ms, 0.0, 0.0)
        vel[2] = self._descent_speed()
        return vel, self._yaw_goal, None

    def _rtl(self) -> Demand:
        cfg, pos = self.v.cfg, self.v.pos
        home_dist = float(np.hypot(pos[0], pos[1]))
        if self.rtl_phase == "climb":
            if self.v.altitude >= cfg.rtl_alt_m - 0.2 or home_dist < 1.0:
                self.rtl_phase = "return"
            else:
                climb_to = np.array([self.target[0], self.target[1], -cfg.rtl_alt_m])
                return self._toward(climb_to, cfg.cruise_speed_ms, cfg.takeoff_speed_ms, 0.0), None, None
        if self.rtl_phase == "return":
            if home_dist < 0.3 and float(np.hypot(*self.v.vel[:2])) < 0.3:
                self.rtl_phase = "land"
                self.target = np.array([0.0, 0.0, pos[2]])
            else:
                goal = np.array([0.0, 0.0, min(pos[2], -cfg.rtl_alt_m) if home_dist >= 1.0 else pos[2]])
                yaw = math.atan2(-pos[1], -pos[0]) if home_dist > 2.0 else None
                return self._toward(goal, cfg.cruise_speed_ms, cfg.takeoff_speed_ms, 0.0), yaw, None
        vel = self._toward(np.array([0.0, 0.0, pos[2]]), cfg.cruise_speed_ms, 0.0, 0.0)
        vel[2] = self._descent_speed()
        return vel, None, None

    def _orbit(self) -> Demand:
        o, cfg, pos = self.orbit_params, self.v.cfg, self.v.pos
        assert o is not None
        rel = pos[:2] - np.array([o.north, o.east])
        dist = float(np.hypot(rel[0], rel[1]))
        r_hat = rel / dist if dist > 1e-3 else np.array([1.0, 0.0])
        t_hat = np.array([-r_hat[1], r_hat[0]])
        speed = float(
            np.clip(
                o.speed,
                -math.sqrt(0.8 * cfg.max_accel_ms2 * o.radius),
                math.sqrt(0.8 * cfg.max_accel_ms2 * o.radius),
            )
        )
        centripetal = speed * speed / o.radius
        vel = np.zeros(3)
        vel[:2] = (
            speed * t_hat
            + cfg.position_gain * (o.radius - dist) * r_hat
            - cfg.speed_time_constant_s * centripetal * r_hat
        )
        vel[2] = float(np.clip(cfg.position_gain * (o.down - pos[2]), -cfg.takeoff_speed_ms, cfg.fast_descent_ms))
        return vel, math.atan2(-r_hat[1], -r_hat[0]), None

    def _offboard(self) -> Demand:
        sp, cfg = self.setpoint, self.v.cfg
        assert sp is not None
        vel = np.zeros(3)
        if sp.position is not None:
            self.target = np.array(sp.position, dtype=float)
            vel = self._toward(self.target, cfg.cruise_speed_ms, cfg.takeoff_speed_ms * 2, cfg.fast_descent_ms)
        if sp.velocity is not None:
            vx, vy, vz = sp.velocity
            if sp.body:
                c, s = math.cos(self.v.yaw), math.sin(self.v.yaw)
                vx, vy = vx * c - vy * s, vx * s + vy * c
            vel = vel + np.array([vx, vy, vz])
        if sp.yaw is not None:
            return vel, sp.yaw, None
        if sp.yaw_rate is not None:
            return vel, None, sp.yaw_rate
        return vel, self._yaw_goal, None
