"""Multicopter kinematics for the simulated vehicle: a velocity loop with a time constant and an
acceleration limit, attitude derived from the commanded acceleration, ground contact, wind, battery.

What the vehicle tries to do (hold, take off, land, RTL, orbit, offboard) is decided by
:mod:`controllers.sim.guidance`; this module turns the resulting velocity demand into motion.
Frames: local NED in metres from home (down = 0 is the ground), yaw in radians from north, clockwise.
Deterministic: the same seed and the same command sequence give the same trajectory.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np

from controllers.sim.guidance import Guidance, Mode, OffboardSetpoint

logger = logging.getLogger(__name__)

GRAVITY = 9.80665
"""m/s^2."""


class CommandRefused(Exception):
    """The vehicle refuses a command; ``temporary`` means it may work later (not armable yet)."""

    def __init__(self, reason: str, *, temporary: bool = False) -> None:
        super().__init__(reason)
        self.temporary = temporary


@dataclass(slots=True)
class PhysicsConfig:
    """Tunables of the simulated airframe and its controllers (defaults are PX4-like)."""

    speed_time_constant_s: float = 0.4
    max_accel_ms2: float = 3.0
    takeoff_speed_ms: float = 1.5
    land_speed_ms: float = 0.7
    fast_descent_ms: float = 1.5
    land_alt1_m: float = 5.0
    cruise_speed_ms: float = 5.0
    position_gain: float = 1.5
    max_yaw_rate_dps: float = 90.0
    attitude_time_constant_s: float = 0.1
    drag_per_ms: float = 0.15
    land_disarm_delay_s: float = 1.0
    preflight_disarm_s: float = 10.0
    battery_flight_minutes: float = 20.0
    battery_start: float = 1.0
    """The battery's charge at boot, 0..1."""
    gps_fix_after_s: float = 0.5
    takeoff_alt_m: float = 2.5
    rtl_alt_m: float = 10.0
    climb_drift_ms: float = 0.0
    """A vertical velocity the controllers do not see (PX4 SIH's EKF: 9.4 m -> 12.1 m in 14 s of velocity setpoints
    with vertical speed 0): a velocity demand is flown this much upwards; position holds correct it."""
    noise: bool = False
    noise_sigma: dict[str, float] = field(default_factory=lambda: {"pos": 0.03, "vel": 0.03, "att_deg": 0.3})


class Multicopter:
    """The simulated airframe. Not thread-safe: the caller serialises access."""

    def __init__(
        self, config: PhysicsConfig | None = None, *, wind: tuple[float, float] = (0.0, 0.0), seed: int = 0
    ) -> None:
        self.cfg = config or PhysicsConfig()
        self.pos = np.zeros(3)
        self.vel = np.zeros(3)
        self.yaw = 0.0
        self.yaw_rate = 0.0
        self.tilt_acc = np.zeros(2)
        self.wind = np.array([wind[0], wind[1], 0.0])
        self.armed = False
        self.in_air = False
        self.battery = self.cfg.battery_start
        self.time_s = 0.0
        self.guidance = Guidance(self)
        self.rng = np.random.default_rng(seed)
        self._armed_at = 0.0
        self._landed_at: float | None = None
        self._flown_since_arm = False
        self.events: list[str] = []
        """What PX4 would say in STATUSTEXT (takeoff/landing detected, auto-disarm); the owner drains it."""

    def _event(self, text: str) -> None:
        self.events.append(text)

    # ----------------------------------------------------------------- state
    @property
    def mode(self) -> Mode:
        return self.guidance.mode

    @property
    def gps_fix(self) -> bool:
        return self.time_s >= self.cfg.gps_fix_after_s

    @property
    def altitude(self) -> float:
        """Metres above home."""
        return -float(self.pos[2])

    def attitude(self) -> tuple[float, float, float]:
        """(roll, pitch, yaw) in radians, consistent with the horizontal thrust acceleration."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        fwd = self.tilt_acc[0] * c + self.tilt_acc[1] * s
        right = -self.tilt_acc[0] * s + self.tilt_acc[1] * c
        pitch = -math.atan2(fwd, GRAVITY)
        roll = math.atan2(right * math.cos(pitch), GRAVITY)
        return roll, pitch, self.yaw

    def battery_voltage(self) -> float:
        """A 4S pack: 16.8 V full, 13.6 V empty, sagging a little under load."""
        sag = 0.3 if self.in_air else 0.0
        return 13.6 + 3.2 * self.battery - sag

    def noisy(self, values: np.ndarray | float, kind: str) -> np.ndarray | float:
        """``values`` plus Gaussian sensor noise of ``kind`` when noise is enabled (seeded)."""
        if not self.cfg.noise:
            return values
        sigma = self.cfg.noise_sigma[kind]
        return values + self.rng.normal(0.0, sigma, np.shape(values))

    # -------------------------------------------------------------- commands
    def arm(self) -> None:
        """Arm on the ground. Raises CommandRefused without a GPS fix or with a flat battery."""
        if self.armed:
            return
        if not self.gps_fix:
            raise CommandRefused("no GPS fix yet", temporary=True)
        if self.battery < 0.05:
            raise CommandRefused("battery empty")
        self.armed = True
        self._armed_at = self.time_s
        self._flown_since_arm = False
        self._event(f"Armed in {self.mode}")

    def disarm(self, *, force: bool = False) -> None:
        """Disarm; refused in the air unless forced (then the vehicle falls)."""
        if self.in_air and not force:
            raise CommandRefused("in air: disarm refused (force with 21196)")
        if self.armed:
            self._event("Disarmed in the air (forced)" if self.in_air else "Disarmed")
        self.armed = False

    def takeoff(self, altitude_m: float | None = None) -> None:
        if not self.armed:
            raise CommandRefused("not armed")
        alt = self.cfg.takeoff_alt_m if altitude_m is None or not math.isfinite(altitude_m) else altitude_m
        self.guidance.takeoff(max(alt, 0.5))

    def set_offboard(self, setpoint: OffboardSetpoint | None) -> None:
        """Switch to offboard flying ``setpoint`` (the caller checks that setpoints stream)."""
        if setpoint is None:
            raise CommandRefused("no offboard setpoint")
        self.guidance.offboard(setpoint)

    # ------------------------------------------------------------------ step
    def step(self, dt: float) -> None:
        """Advance the simulation by ``dt`` seconds."""
        cfg = self.cfg
        self.time_s += dt
        if not self.armed:
            self._step_unpowered(dt)
            return
        v_cmd, yaw_goal, yaw_rate = self.guidance.demand()
        if not self.in_air and v_cmd[2] >= -0.05:
            self._idle_on_ground()
            return
        a_cmd = (v_cmd - self.vel) / cfg.speed_time_constant_s
        a_cmd[2] -= cfg.climb_drift_ms / cfg.speed_time_constant_s
        h = float(np.hypot(a_cmd[0], a_cmd[1]))
        if h > cfg.max_accel_ms2:
            a_cmd[:2] *= cfg.max_accel_ms2 / h
        a_cmd[2] = float(np.clip(a_cmd[2], -cfg.max_accel_ms2, cfg.max_accel_ms2))
        # The controllers cancel still-air drag; what the wind adds is an unmodelled disturbance.
        push = cfg.drag_per_ms * self.wind if self.in_air else np.zeros(3)
        self._integrate(a_cmd + push, dt)
        alpha = min(1.0, dt / cfg.attitude_time_constant_s)
        self.tilt_acc += alpha * (a_cmd[:2] - self.tilt_acc)
        self._turn(yaw_goal, yaw_rate, dt)
        self._drain(dt)

    def _integrate(self, acc: np.ndarray, dt: float) -> None:
        self.vel += acc * dt
        self.pos += self.vel * dt
        if self.pos[2] < -0.1 and not self.in_air:
            self._event("Takeoff detected")
            self.in_air = True
            self._flown_since_arm = True
            self._landed_at = None
        if self.pos[2] >= 0.0:
            self.pos[2] = 0.0
            if self.in_air and self.vel[2] >= 0.0:
                self._touchdown()

    def _touchdown(self) -> None:
        self.in_air = False
        self.vel[:] = 0.0
        self.tilt_acc[:] = 0.0
        self._landed_at = self.time_s
        self.guidance.on_touchdown()
        self._event(f"Landing detected at n={self.pos[0]:.1f} e={self.pos[1]:.1f}")

    def _idle_on_ground(self) -> None:
        """Armed on the ground: PX4 disarms after landing and if it never takes off."""
        self.vel[:] = 0.0
        self.tilt_acc[:] = 0.0
        if self._landed_at is not None and self.time_s - self._landed_at >= self.cfg.land_disarm_delay_s:
            self.armed = False
            self.guidance.hold()
            self._event("Disarmed by landing")
        elif not self._flown_since_arm and self.time_s - self._armed_at >= self.cfg.preflight_disarm_s:
            self.armed = False
            self._event("Disarmed: no takeoff after arming")

    def _step_unpowered(self, dt: float) -> None:
        self.tilt_acc[:] = 0.0
        if not self.in_air:
            self.vel[:] = 0.0
            return
        acc = self.cfg.drag_per_ms * (self.wind - self.vel)
        acc[2] = GRAVITY
        self._integrate(acc, dt)

    def _turn(self, yaw_goal: float | None, yaw_rate: float | None, dt: float) -> None:
        max_rate = math.radians(self.cfg.max_yaw_rate_dps)
        if yaw_goal is not None:
            err = (yaw_goal - self.yaw + math.pi) % (2 * math.pi) - math.pi
            rate = float(np.clip(err / max(dt, 0.25), -max_rate, max_rate))
        elif yaw_rate is not None:
            rate = float(np.clip(yaw_rate, -max_rate, max_rate))
        else:
            rate = 0.0
        self.yaw_rate = rate
        self.yaw = (self.yaw + rate * dt + math.pi) % (2 * math.pi) - math.pi

    def _drain(self, dt: float) -> None:
        per_s = 1.0 / (self.cfg.battery_flight_minutes * 60.0)
        self.battery = max(0.0, self.battery - dt * (per_s if self.in_air else 0.1 * per_s))
