"""The simulated vehicle's gimbal: two axes (pitch, yaw; roll held level) behind a gimbal manager on the autopilot's
own component, speaking MAVLink's gimbal protocol v2 the way MAVSDK's Gimbal plugin discovers and drives it.

Discovery: MAVSDK asks each component it hears a heartbeat from for GIMBAL_MANAGER_INFORMATION
(MAV_CMD_REQUEST_MESSAGE); the manager names gimbal device 1 (a non-MAVLink device the manager answers for, ids
1..6), and MAVSDK then asks the same component for GIMBAL_DEVICE_INFORMATION and listens to
GIMBAL_DEVICE_ATTITUDE_STATUS and GIMBAL_MANAGER_STATUS, streamed by :class:`~controllers.sim.streams.TelemetryStreams`.
Control: MAV_CMD_DO_GIMBAL_MANAGER_CONFIGURE takes (param1/2 = a system/component) or releases (-3: "release if I
have it") primary control; setpoints come as GIMBAL_MANAGER_SET_ATTITUDE (streamed: a quaternion or angular rates,
the other NaN) or MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW (once), and are taken from the primary controller only (from
anyone while nobody has control, as ArduPilot does).

A rate setpoint keeps the gimbal turning until another setpoint comes (it does not time out): a client that wants
it to stop must say so. A release stops it where it is. Pitch is the angle above the horizon (stabilised), yaw
relative to the vehicle's nose.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink

from controllers.quaternion import euler, quaternion

M = mavlink

DEVICE_ID = 1
"""The gimbal device's id in every gimbal message: 1, a device without a MAVLink component of its own."""

PITCH_LIMITS_DEG = (-90.0, 30.0)
YAW_LIMITS_DEG = (-180.0, 180.0)
"""Yaw is continuous (a slip ring: ``SUPPORTS_INFINITE_YAW``); reported and aimed within these."""
MAX_RATE_DEG_S = 180.0
"""The fastest the motors turn, each axis; angle setpoints are approached at this rate."""

NEUTRAL_PITCH_DEG = -45.0
"""Where the gimbal looks at boot: 45 degrees down, ahead."""

CAP_FLAGS = (M.GIMBAL_MANAGER_CAP_FLAGS_HAS_NEUTRAL | M.GIMBAL_MANAGER_CAP_FLAGS_HAS_PITCH_AXIS
             | M.GIMBAL_MANAGER_CAP_FLAGS_HAS_PITCH_LOCK | M.GIMBAL_MANAGER_CAP_FLAGS_HAS_YAW_AXIS
             | M.GIMBAL_MANAGER_CAP_FLAGS_HAS_YAW_FOLLOW | M.GIMBAL_MANAGER_CAP_FLAGS_HAS_YAW_LOCK
             | M.GIMBAL_MANAGER_CAP_FLAGS_SUPPORTS_INFINITE_YAW)
"""What the manager and the device say they can do (the device's flags have the same values)."""

RELEASE_IF_MINE = -3
"""DO_GIMBAL_MANAGER_CONFIGURE: release control if the sender has it."""
SET_SENDER = -2
"""DO_GIMBAL_MANAGER_CONFIGURE: give control to the sender."""
LEAVE = -1
"""DO_GIMBAL_MANAGER_CONFIGURE: leave control unchanged."""


@dataclass(slots=True)
class Setpoint:
    """What the gimbal is told: angles to reach (degrees) or rates to turn at (deg/s), per axis (None: no target)."""

    pitch_deg: float | None = None
    yaw_deg: float | None = None
    pitch_rate: float = 0.0
    yaw_rate: float = 0.0


class SimGimbal:
    """The gimbal's state, what commands and setpoints do to it, and the messages that report it."""

    def __init__(self) -> None:
        self.pitch_deg = NEUTRAL_PITCH_DEG
        """Above the horizon (negative: down)."""
        self.yaw_deg = 0.0
        """Relative to the vehicle's nose, positive right."""
        self.pitch_rate = 0.0
        self.yaw_rate = 0.0
        """The rates it turns at now (deg/s), for the attitude status."""
        self.setpoint = Setpoint(NEUTRAL_PITCH_DEG, 0.0)
        self.primary: tuple[int, int] = (0, 0)
        """(system, component) in primary control; (0, 0): nobody."""
        self.setpoints = 0
        """Setpoints accepted (tests)."""

    # ------------------------------------------------------------------- control
    def configure(self, p1: float, p2: float, sender: tuple[int, int]) -> int:
        """MAV_CMD_DO_GIMBAL_MANAGER_CONFIGURE's primary-control parameters from ``sender``; a MAV_RESULT."""
        if not (math.isfinite(p1) and math.isfinite(p2)):
            return M.MAV_RESULT_DENIED
        sysid, compid = int(p1), int(p2)
        if sysid == LEAVE:
            return M.MAV_RESULT_ACCEPTED
        if sysid == RELEASE_IF_MINE:
            if self.primary == sender:
                self.release()
            return M.MAV_RESULT_ACCEPTED
        self.primary = sender if sysid == SET_SENDER else (sysid, compid)
        return M.MAV_RESULT_ACCEPTED

    def release(self) -> None:
        """Nobody in control: stop turning, stay where it is."""
        self.primary = (0, 0)
        self.setpoint = Setpoint(self.pitch_deg, self.yaw_deg)

    def may_command(self, sender: tuple[int, int]) -> bool:
        return self.primary in ((0, 0), sender)

    def set_attitude(self, msg: mavlink.MAVLink_gimbal_manager_set_attitude_message, vehicle_yaw_deg: float) -> bool:
        """GIMBAL_MANAGER_SET_ATTITUDE: a quaternion (angles) or angular rates (rad/s); False when not taken."""
        sender = (msg.get_srcSystem(), msg.get_srcComponent())
        if msg.gimbal_device_id not in (0, DEVICE_ID) or not self.may_command(sender):
            return False
        q = tuple(float(c) for c in msg.q)
        rates = (msg.angular_velocity_y, msg.angular_velocity_z)
        if all(math.isfinite(c) for c in q):
            _, pitch, yaw = (math.degrees(a) for a in euler(q))
            self._angles(pitch, yaw, msg.flags, vehicle_yaw_deg)
        elif all(math.isfinite(r) for r in rates):
            self.setpoint = Setpoint(pitch_rate=math.degrees(rates[0]), yaw_rate=math.degrees(rates[1]))
        else:
            return False
        self.setpoints += 1
        return True

    def pitchyaw(self, p: list[float], flags: int, sender: tuple[int, int], vehicle_yaw_deg: float) -> int:
        """MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW: angles (param 1, 2) or rates (3, 4), degrees; a MAV_RESULT."""
        if not self.may_command(sender):
            return M.MAV_RESULT_DENIED
        if math.isfinite(p[0]) and math.isfinite(p[1]):
            self._angles(p[0], p[1], flags, vehicle_yaw_deg)
        elif math.isfinite(p[2]) and math.isfinite(p[3]):
            self.setpoint = Setpoint(pitch_rate=p[2], yaw_rate=p[3])
        else:
            return M.MAV_RESULT_DENIED
        self.setpoints += 1
        return M.MAV_RESULT_ACCEPTED

    def _angles(self, pitch: float, yaw: float, flags: int, vehicle_yaw_deg: float) -> None:
        if flags & (M.GIMBAL_MANAGER_FLAGS_YAW_LOCK | M.GIMBAL_MANAGER_FLAGS_YAW_IN_EARTH_FRAME):
            yaw -= vehicle_yaw_deg  # an earth-frame yaw: where the nose points now
        self.setpoint = Setpoint(_clamp(pitch, PITCH_LIMITS_DEG), _wrap(yaw))

    # ------------------------------------------------------------------- motion
    def step(self, dt: float) -> None:
        """Turn for ``dt`` seconds towards the angle setpoint, or at the rate setpoint, within the limits."""
        sp = self.setpoint
        self.pitch_deg, self.pitch_rate = _move(self.pitch_deg, sp.pitch_deg, sp.pitch_rate, PITCH_LIMITS_DEG, dt)
        yaw_target = None if sp.yaw_deg is None else self.yaw_deg + _wrap(sp.yaw_deg - self.yaw_deg)  # the short way
        yaw, self.yaw_rate = _move(self.yaw_deg, yaw_target, sp.yaw_rate, None, dt)
        self.yaw_deg = _wrap(yaw)

    # ------------------------------------------------------------------ messages
    def attitude_status(self, enc: mavlink.MAVLink, boot_ms: int) -> mavlink.MAVLink_message:
        """GIMBAL_DEVICE_ATTITUDE_STATUS: pitch from the horizon, yaw in the vehicle's frame (flagged so)."""
        flags = (M.GIMBAL_DEVICE_FLAGS_ROLL_LOCK | M.GIMBAL_DEVICE_FLAGS_PITCH_LOCK
                 | M.GIMBAL_DEVICE_FLAGS_YAW_IN_VEHICLE_FRAME)
        q = quaternion(0.0, math.radians(self.pitch_deg), math.radians(self.yaw_deg))
        return enc.gimbal_device_attitude_status_encode(0, 0, boot_ms, flags, q, 0.0, math.radians(self.pitch_rate),
                                                        math.radians(self.yaw_rate), 0, math.nan, math.nan, DEVICE_ID)

    def manager_status(self, enc: mavlink.MAVLink, boot_ms: int) -> mavlink.MAVLink_message:
        flags = M.GIMBAL_MANAGER_FLAGS_ROLL_LOCK | M.GIMBAL_MANAGER_FLAGS_PITCH_LOCK
        return enc.gimbal_manager_status_encode(boot_ms, flags, DEVICE_ID, *self.primary, 0, 0)

    def manager_information(self, enc: mavlink.MAVLink, boot_ms: int) -> mavlink.MAVLink_message:
        pitch, yaw = (tuple(math.radians(a) for a in limits) for limits in (PITCH_LIMITS_DEG, YAW_LIMITS_DEG))
        return enc.gimbal_manager_information_encode(boot_ms, CAP_FLAGS, DEVICE_ID, 0.0, 0.0, *pitch, *yaw)

    def device_information(self, enc: mavlink.MAVLink, boot_ms: int) -> mavlink.MAVLink_message:
        pitch, yaw = (tuple(math.radians(a) for a in limits) for limits in (PITCH_LIMITS_DEG, YAW_LIMITS_DEG))
        return enc.gimbal_device_information_encode(boot_ms, b"uav-tui", b"sim 2-axis gimbal", b"", 0, 0, 0,
                                                    CAP_FLAGS, 0, 0.0, 0.0, *pitch, *yaw, DEVICE_ID)

    def truth(self) -> dict[str, float | bool]:
        """For the truth channel: the angles, the rates, and whether someone has control."""
        return {"gimbal_pitch": self.pitch_deg, "gimbal_yaw": self.yaw_deg, "gimbal_pitch_rate": self.pitch_rate,
                "gimbal_yaw_rate": self.yaw_rate, "gimbal_controlled": self.primary != (0, 0)}


def _move(angle: float, target: float | None, rate: float, limits: tuple[float, float] | None,
          dt: float) -> tuple[float, float]:
    """(new angle, rate turned at) after ``dt``: towards ``target`` at the motors' speed, or at ``rate`` (within
    ``limits``; None: no limit)."""
    if target is not None:
        step = max(-MAX_RATE_DEG_S * dt, min(MAX_RATE_DEG_S * dt, target - angle))
        return angle + step, step / dt if dt > 0 else 0.0
    rate = max(-MAX_RATE_DEG_S, min(MAX_RATE_DEG_S, rate))
    new = angle + rate * dt if limits is None else _clamp(angle + rate * dt, limits)
    return new, (new - angle) / dt if dt > 0 else 0.0


def _clamp(value: float, limits: tuple[float, float]) -> float:
    return max(limits[0], min(limits[1], value))


def _wrap(deg: float) -> float:
    return (deg + 180.0) % 360.0 - 180.0
