"""Telemetry the simulated vehicle sends: one builder per MAVLink message and a rate scheduler
that honours SET_MESSAGE_INTERVAL. Default rates resemble PX4 SITL's."""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np
from pymavlink.dialects.v20 import common as mavlink

from controllers.autopilots import Autopilot
from controllers.quaternion import quaternion
from controllers.sim.dialect import DIALECTS, Dialect
from controllers.sim.geo import Home
from controllers.sim.gimbal import SimGimbal
from controllers.sim.guidance import Mode
from controllers.sim.physics import Multicopter

M = mavlink
DEFAULT_RATES_HZ: dict[int, float] = {
    M.MAVLINK_MSG_ID_HEARTBEAT: 1.0,
    M.MAVLINK_MSG_ID_SYS_STATUS: 5.0,
    M.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: 5.0,
    M.MAVLINK_MSG_ID_ATTITUDE: 50.0,
    M.MAVLINK_MSG_ID_ATTITUDE_QUATERNION: 50.0,
    M.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: 25.0,
    M.MAVLINK_MSG_ID_LOCAL_POSITION_NED: 25.0,
    M.MAVLINK_MSG_ID_GPS_RAW_INT: 5.0,
    M.MAVLINK_MSG_ID_HOME_POSITION: 0.5,
    M.MAVLINK_MSG_ID_BATTERY_STATUS: 1.0,
    M.MAVLINK_MSG_ID_VFR_HUD: 4.0,
    M.MAVLINK_MSG_ID_SYSTEM_TIME: 1.0,
    M.MAVLINK_MSG_ID_DISTANCE_SENSOR: 10.0,
    M.MAVLINK_MSG_ID_GIMBAL_DEVICE_ATTITUDE_STATUS: 20.0,
    M.MAVLINK_MSG_ID_GIMBAL_MANAGER_STATUS: 5.0,
    M.MAVLINK_MSG_ID_ALTITUDE: 10.0,
    M.MAVLINK_MSG_ID_TERRAIN_REPORT: 10.0,
    M.MAVLINK_MSG_ID_RC_CHANNELS: 5.0,
}
"""Streamed at boot, in Hz."""
RANGEFINDER_CM = (5, 4000)
"""The simulated downward rangefinder's range, centimetres (a LiDAR-Lite v3's)."""
_SLACK_S = 0.005
"""A message due this close to the current tick goes now, so 50 Hz streams survive tick jitter."""

_SENSORS = (
    M.MAV_SYS_STATUS_SENSOR_3D_GYRO
    | M.MAV_SYS_STATUS_SENSOR_3D_ACCEL
    | M.MAV_SYS_STATUS_SENSOR_3D_MAG
    | M.MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE
    | M.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL
    | M.MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION
    | M.MAV_SYS_STATUS_SENSOR_YAW_POSITION
    | M.MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL
    | M.MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL
    | M.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS
    | M.MAV_SYS_STATUS_AHRS
    | M.MAV_SYS_STATUS_SENSOR_BATTERY
)
_GPS = M.MAV_SYS_STATUS_SENSOR_GPS
_PREARM = M.MAV_SYS_STATUS_PREARM_CHECK
_RC = M.MAV_SYS_STATUS_SENSOR_RC_RECEIVER


def landed_state(v: Multicopter) -> int:
    """MAV_LANDED_STATE the way PX4's land detector reports it."""
    if v.mode == Mode.TAKEOFF and v.armed:
        return M.MAV_LANDED_STATE_TAKEOFF
    if not v.in_air:
        return M.MAV_LANDED_STATE_ON_GROUND
    if v.mode in (Mode.LAND, Mode.PRECLAND) or (v.mode == Mode.RTL and v.guidance.rtl_phase == "land"):
        return M.MAV_LANDED_STATE_LANDING
    return M.MAV_LANDED_STATE_IN_AIR


class TelemetryStreams:
    """Builds telemetry messages from a :class:`Multicopter` and decides which are due."""

    def __init__(self, encoder: mavlink.MAVLink, vehicle: Multicopter, home: Home, *,
                 gps_clock_offset_s: float = 0.0, dialect: Dialect = DIALECTS[Autopilot.PX4],
                 gimbal: SimGimbal | None = None) -> None:
        self.enc = encoder
        self.dialect = dialect
        self.v = vehicle
        self.home = home
        self.gps_clock_offset_s = gps_clock_offset_s
        """How far the UTC time in SYSTEM_TIME is from this computer's clock (a ground computer's clock is wrong)."""
        self._boot_ns = time.monotonic_ns()
        self.link_quality_pct: float | None = None
        """The RC receiver's signal RC_CHANNELS reports, percent; None: no receiver (chancount 0, rssi unknown)."""
        self.gimbal = gimbal or SimGimbal()
        self._builders: dict[int, Callable[[], mavlink.MAVLink_message]] = {
            M.MAVLINK_MSG_ID_HEARTBEAT: self.heartbeat,
            M.MAVLINK_MSG_ID_SYS_STATUS: self.sys_status,
            M.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: self.extended_sys_state,
            M.MAVLINK_MSG_ID_ATTITUDE: self.attitude,
            M.MAVLINK_MSG_ID_ATTITUDE_QUATERNION: self.attitude_quaternion,
            M.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: self.global_position_int,
            M.MAVLINK_MSG_ID_LOCAL_POSITION_NED: self.local_position_ned,
            M.MAVLINK_MSG_ID_GPS_RAW_INT: self.gps_raw_int,
            M.MAVLINK_MSG_ID_HOME_POSITION: self.home_position,
            M.MAVLINK_MSG_ID_BATTERY_STATUS: self.battery_status,
            M.MAVLINK_MSG_ID_VFR_HUD: self.vfr_hud,
            M.MAVLINK_MSG_ID_SYSTEM_TIME: self.system_time,
            M.MAVLINK_MSG_ID_DISTANCE_SENSOR: self.distance_sensor,
            M.MAVLINK_MSG_ID_ALTITUDE: self.altitude,
            M.MAVLINK_MSG_ID_TERRAIN_REPORT: self.terrain_report,
            M.MAVLINK_MSG_ID_RC_CHANNELS: self.rc_channels,
            M.MAVLINK_MSG_ID_AUTOPILOT_VERSION: self.autopilot_version,
        }
        g = self.gimbal
        for mid, build in ((M.MAVLINK_MSG_ID_GIMBAL_DEVICE_ATTITUDE_STATUS, g.attitude_status),
                           (M.MAVLINK_MSG_ID_GIMBAL_MANAGER_STATUS, g.manager_status),
                           (M.MAVLINK_MSG_ID_GIMBAL_MANAGER_INFORMATION, g.manager_information),
                           (M.MAVLINK_MSG_ID_GIMBAL_DEVICE_INFORMATION, g.device_information)):
            self._builders[mid] = self._stamped(build)
        self._interval = {mid: 1.0 / hz for mid, hz in DEFAULT_RATES_HZ.items()}
        self._next = dict.fromkeys(self._interval, 0.0)

    def _stamped(self, build: Callable[[mavlink.MAVLink, int], mavlink.MAVLink_message],
                 ) -> Callable[[], mavlink.MAVLink_message]:
        """A builder of this encoder's message stamped with the boot time (the gimbal's messages)."""
        return lambda: build(self.enc, self.boot_ms())

    # ------------------------------------------------------------ scheduling
    def can_build(self, msg_id: int) -> bool:
        return msg_id in self._builders

    def build(self, msg_id: int) -> mavlink.MAVLink_message:
        return self._builders[msg_id]()

    def set_interval(self, msg_id: int, interval_us: float) -> bool:
        """SET_MESSAGE_INTERVAL: -1 stops, 0 restores the default, >0 sets. False if unknown."""
        if msg_id not in self._builders:
            return False
        if interval_us < 0:
            self._interval.pop(msg_id, None)
        elif interval_us == 0:
            if msg_id in DEFAULT_RATES_HZ:
                self._interval[msg_id] = 1.0 / DEFAULT_RATES_HZ[msg_id]
            else:
                self._interval.pop(msg_id, None)
        else:
            self._interval[msg_id] = interval_us * 1e-6
        self._next[msg_id] = 0.0
        return True

    def due(self, now_s: float) -> list[mavlink.MAVLink_message]:
        """Messages whose time has come; at most one of each per call."""
        out = []
        for mid, interval in self._interval.items():
            if self._next.get(mid, 0.0) <= now_s + _SLACK_S:
                planned = self._next.get(mid, 0.0) + interval
                self._next[mid] = planned if planned > now_s else now_s + interval
                out.append(self._builders[mid]())
        return out

    # ------------------------------------------------------------- builders
    def boot_ms(self) -> int:
        return ((time.monotonic_ns() - self._boot_ns) // 1_000_000) & 0xFFFFFFFF

    def _nav(self) -> tuple[np.ndarray, np.ndarray, tuple[float, float, float]]:
        v = self.v
        pos = np.asarray(v.noisy(v.pos, "pos"))
        vel = np.asarray(v.noisy(v.vel, "vel"))
        roll, pitch, yaw = v.attitude()
        if v.cfg.noise:
            roll, pitch, yaw = (a + math.radians(float(v.noisy(0.0, "att_deg"))) for a in (roll, pitch, yaw))
        return pos, vel, (roll, pitch, yaw)

    def heartbeat(self) -> mavlink.MAVLink_message:
        v = self.v
        status = M.MAV_STATE_ACTIVE if v.armed else M.MAV_STATE_STANDBY
        return self.enc.heartbeat_encode(
            M.MAV_TYPE_QUADROTOR,
            self.dialect.autopilot,
            self.dialect.modes.base_mode(v.mode, v.armed),
            self.dialect.modes.custom_mode(v.mode),
            status,
        )

    def sys_status(self) -> mavlink.MAVLink_message:
        v = self.v
        present = _SENSORS | _GPS | _PREARM | (_RC if v.guidance.radio else 0)
        health = _SENSORS | _RC | ((_GPS | _PREARM) if v.gps_fix else 0)  # PX4: an absent receiver is "healthy"
        return self.enc.sys_status_encode(
            present,
            present,
            health,
            250,
            int(v.battery_voltage() * 1000),
            1200 if v.in_air else 50,
            int(round(v.battery * 100)),
            0,
            0,
            0,
            0,
            0,
            0,
        )

    def extended_sys_state(self) -> mavlink.MAVLink_message:
        return self.enc.extended_sys_state_encode(M.MAV_VTOL_STATE_MC, landed_state(self.v))

    def attitude(self) -> mavlink.MAVLink_message:
        _, _, (roll, pitch, yaw) = self._nav()
        return self.enc.attitude_encode(self.boot_ms(), roll, pitch, yaw, 0.0, 0.0, self.v.yaw_rate)

    def attitude_quaternion(self) -> mavlink.MAVLink_message:
        _, _, (roll, pitch, yaw) = self._nav()
        return self.enc.attitude_quaternion_encode(self.boot_ms(), *quaternion(roll, pitch, yaw), 0.0, 0.0,
                                                   self.v.yaw_rate)

    def global_position_int(self) -> mavlink.MAVLink_message:
        pos, vel, (_, _, yaw) = self._nav()
        lat, lon, alt = self.home.to_global(*pos)
        hdg = int(round(math.degrees(yaw) * 100)) % 36000
        return self.enc.global_position_int_encode(
            self.boot_ms(),
            int(round(lat * 1e7)),
            int(round(lon * 1e7)),
            int(round(alt * 1000)),
            int(round(-pos[2] * 1000)),
            *(int(round(x * 100)) for x in vel),
            hdg,
        )

    def local_position_ned(self) -> mavlink.MAVLink_message:
        pos, vel, _ = self._nav()
        return self.enc.local_position_ned_encode(self.boot_ms(), *(float(x) for x in pos), *(float(x) for x in vel))

    def distance_sensor(self) -> mavlink.MAVLink_message:
        """A downward rangefinder over the flat ground: the range along the body's down axis; beyond its
        maximum (or tilted past 80 degrees) it reports maximum + 1 cm, out of range."""
        pos, _, (roll, pitch, _) = self._nav()
        low, high = RANGEFINDER_CM
        tilt = math.cos(roll) * math.cos(pitch)
        reading = -pos[2] * 100 / tilt if tilt > math.cos(math.radians(80)) else high + 1
        current = int(round(min(max(reading, 0), high + 1)))
        return self.enc.distance_sensor_encode(self.boot_ms(), low, high, current, M.MAV_DISTANCE_SENSOR_LASER, 0,
                                               M.MAV_SENSOR_ROTATION_PITCH_270, 0)

    def altitude(self) -> mavlink.MAVLink_message:
        """ALTITUDE as PX4 sends it: ``altitude_terrain`` the terrain's local altitude (its flat ground: 0),
        ``bottom_clearance`` the height over it."""
        pos, _, _ = self._nav()
        height = -float(pos[2])
        amsl = self.home.alt_m + height
        return self.enc.altitude_encode(self.boot_ms() * 1000, amsl, amsl, height, height, 0.0, height)

    def terrain_report(self) -> mavlink.MAVLink_message:
        """TERRAIN_REPORT as ArduPilot streams it with terrain data loaded: the flat ground at home's altitude."""
        pos, _, _ = self._nav()
        lat, lon, _ = self.home.to_global(*pos)
        return self.enc.terrain_report_encode(int(round(lat * 1e7)), int(round(lon * 1e7)), 100, self.home.alt_m,
                                              -float(pos[2]), 0, 16)

    def rc_channels(self) -> mavlink.MAVLink_message:
        """RC_CHANNELS: eight centred channels and ``link_quality_pct`` as rssi 0-254; without it no channels and
        rssi 255 (unknown)."""
        pct = self.link_quality_pct
        count, rssi = (0, 255) if pct is None else (8, int(round(max(0.0, min(100.0, pct)) * 2.54)))
        channels = [1500 if i < count else 65535 for i in range(18)]
        return self.enc.rc_channels_encode(self.boot_ms(), count, *channels, rssi)

    def gps_raw_int(self) -> mavlink.MAVLink_message:
        v = self.v
        pos, vel, _ = self._nav()
        lat, lon, alt = self.home.to_global(*pos)
        fix, sats = (M.GPS_FIX_TYPE_3D_FIX, 12) if v.gps_fix else (M.GPS_FIX_TYPE_NO_FIX, 3)
        speed = float(np.hypot(vel[0], vel[1]))
        cog = int(round(math.degrees(math.atan2(vel[1], vel[0])) * 100)) % 36000 if speed > 0.2 else 65535
        return self.enc.gps_raw_int_encode(
            time.time_ns() // 1000,
            fix,
            int(round(lat * 1e7)),
            int(round(lon * 1e7)),
            int(round(alt * 1000)),
            80,
            120,
            int(round(speed * 100)),
            cog,
            sats,
            0,
            500,
            800,
            200,
            0,
        )

    def home_position(self) -> mavlink.MAVLink_message:
        h = self.home
        return self.enc.home_position_encode(
            int(round(h.lat_deg * 1e7)),
            int(round(h.lon_deg * 1e7)),
            int(round(h.alt_m * 1000)),
            0.0,
            0.0,
            0.0,
            [1.0, 0.0, 0.0, 0.0],
            0.0,
            0.0,
            0.0,
            time.time_ns() // 1000,
        )

    def battery_status(self) -> mavlink.MAVLink_message:
        v = self.v
        voltages = [int(v.battery_voltage() * 1000)] + [65535] * 9
        used_mah = int((1.0 - v.battery) * 5000)
        return self.enc.battery_status_encode(
            0,
            M.MAV_BATTERY_FUNCTION_ALL,
            M.MAV_BATTERY_TYPE_LIPO,
            2500,
            voltages,
            1200 if v.in_air else 50,
            used_mah,
            -1,
            int(round(v.battery * 100)),
        )

    def vfr_hud(self) -> mavlink.MAVLink_message:
        v = self.v
        speed = float(np.hypot(v.vel[0], v.vel[1]))
        heading = int(round(math.degrees(v.yaw))) % 360
        return self.enc.vfr_hud_encode(
            speed, speed, heading, 50 if v.in_air else 0, v.altitude + self.home.alt_m, -float(v.vel[2])
        )

    def system_time(self) -> mavlink.MAVLink_message:
        """UTC from GPS once there is a fix (0 before, as PX4 sends it), and the boot time."""
        unix_us = round((time.time() + self.gps_clock_offset_s) * 1e6) if self.v.gps_fix else 0
        return self.enc.system_time_encode(unix_us, self.boot_ms())

    def autopilot_version(self) -> mavlink.MAVLink_message:
        return self.enc.autopilot_version_encode(
            self.dialect.capabilities,
            self.dialect.sw_version,
            0,
            0,
            0,
            [0] * 8,
            [0] * 8,
            [0] * 8,
            0,
            0,
            0x5349_4D55_4156,
        )
