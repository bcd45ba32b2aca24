"""COMMAND_LONG / COMMAND_INT and the parameter protocol, answered the way PX4 (or, in the ``ardupilot``
dialect, ArduCopter) answers them.

Every command gets a COMMAND_ACK: ACCEPTED, DENIED, TEMPORARILY_REJECTED, or UNSUPPORTED for
commands the simulator does not implement.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from pymavlink.dialects.v20 import common as mavlink

from controllers.sim.guidance import OFFBOARD_LOSS_ACTIONS, Mode, Orbit
from controllers.sim.params import Param, ParamStore, encode_value
from controllers.sim.physics import CommandRefused

if TYPE_CHECKING:
    from controllers.sim.vehicle import SimVehicleServer

logger = logging.getLogger(__name__)

M = mavlink
FORCE_MAGIC = 21196
"""param2 of ARM_DISARM that forces a disarm in the air (PX4)."""
ACCEPTED, DENIED, TEMP_REJECTED, UNSUPPORTED = (
    M.MAV_RESULT_ACCEPTED,
    M.MAV_RESULT_DENIED,
    M.MAV_RESULT_TEMPORARILY_REJECTED,
    M.MAV_RESULT_UNSUPPORTED,
)
_INT_UNSET = (0, 0x7FFFFFFF, -0x80000000)
"""COMMAND_INT x/y values that mean 'not given' (MAVSDK sends NaN as INT32_MIN)."""


class Cmd:
    """One command with its parameters, whichever message carried it (x/y are degrees or None)."""

    def __init__(self, msg: mavlink.MAVLink_message) -> None:
        self.id = msg.command
        self.src = (msg.get_srcSystem(), msg.get_srcComponent())
        self.p = [msg.param1, msg.param2, msg.param3, msg.param4]
        is_int = msg.get_type() == "COMMAND_INT"
        self.p5 = float(msg.x if is_int else msg.param5)
        """Parameter 5 as sent (COMMAND_INT: ``x``, unscaled): flags, for the gimbal commands."""
        if is_int:
            self.x = None if msg.x in _INT_UNSET else msg.x * 1e-7
            self.y = None if msg.y in _INT_UNSET else msg.y * 1e-7
            self.z = msg.z
        else:
            self.x = msg.param5 if math.isfinite(msg.param5) and msg.param5 != 0 else None
            self.y = msg.param6 if math.isfinite(msg.param6) and msg.param6 != 0 else None
            self.z = msg.param7


class CommandHandler:
    """Executes commands and parameter requests on a :class:`SimVehicleServer` (caller holds its lock)."""

    def __init__(self, server: SimVehicleServer) -> None:
        self.s = server
        self.v = server.vehicle
        self._handlers: dict[int, Callable[[Cmd], int]] = {
            M.MAV_CMD_COMPONENT_ARM_DISARM: self._arm_disarm,
            M.MAV_CMD_NAV_TAKEOFF: self._takeoff,
            M.MAV_CMD_NAV_LAND: self._mode_action(self._land),
            M.MAV_CMD_NAV_RETURN_TO_LAUNCH: self._mode_action(lambda c: self.v.guidance.rtl()),
            M.MAV_CMD_DO_SET_MODE: self._set_mode,
            M.MAV_CMD_DO_ORBIT: self._orbit,
            M.MAV_CMD_DO_REPOSITION: self._reposition,
            M.MAV_CMD_DO_CHANGE_SPEED: self._change_speed,
            M.MAV_CMD_SET_MESSAGE_INTERVAL: self._message_interval,
            M.MAV_CMD_REQUEST_MESSAGE: self._request_message,
            M.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES: self._capabilities,
            M.MAV_CMD_DO_GIMBAL_MANAGER_CONFIGURE: lambda c: self.s.gimbal.configure(c.p[0], c.p[1], c.src),
            M.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW: self._gimbal_pitchyaw,
        }
        self.params = ParamStore(self._param_list())
        self._after_ack: list[mavlink.MAVLink_message] = []
        """Messages a command asked for, sent right after its COMMAND_ACK."""

    def _param_list(self) -> list[Param]:
        cfg, pc, stick = self.s.cfg, self.v.cfg, self.v.guidance.stick

        def bind(name: str, obj: object, attr: str) -> Param:
            return Param(
                name,
                M.MAV_PARAM_TYPE_REAL32,
                lambda: getattr(obj, attr),
                lambda value: setattr(obj, attr, value),
            )

        if stick is not None:  # the ArduCopter dialect: the parameters it simulates
            pad = self.s.pad
            return [
                Param("PLND_ENABLED", M.MAV_PARAM_TYPE_INT8, lambda: int(pad.enabled),
                      lambda value: setattr(pad, "enabled", bool(value))),
                Param("PLND_TYPE", M.MAV_PARAM_TYPE_INT8, lambda: pad.source_type,
                      lambda value: setattr(pad, "source_type", int(value))),
                bind("GUID_TIMEOUT", cfg, "guided_timeout_s"),
                bind("PILOT_SPD_UP", stick, "speed_up_ms"),
                bind("PILOT_SPD_DN", stick, "speed_dn_ms"),
                *ParamStore.constants(GUID_OPTIONS=0),
                *ParamStore.settable(FENCE_ENABLE=0, FENCE_ACTION=1, FENCE_TYPE=7, FENCE_RADIUS=150.0,
                                     FENCE_ALT_MAX=100.0),  # ArduCopter's defaults: no fence
            ]
        return [
            bind("MIS_TAKEOFF_ALT", pc, "takeoff_alt_m"),
            bind("RTL_RETURN_ALT", pc, "rtl_alt_m"),
            bind("MPC_XY_CRUISE", pc, "cruise_speed_ms"),
            bind("MPC_LAND_SPEED", pc, "land_speed_ms"),
            bind("MPC_TKO_SPEED", pc, "takeoff_speed_ms"),
            bind("MPC_ACC_HOR", pc, "max_accel_ms2"),
            bind("COM_DISARM_LAND", pc, "land_disarm_delay_s"),
            bind("COM_DISARM_PRFLT", pc, "preflight_disarm_s"),
            bind("COM_OF_LOSS_T", cfg, "offboard_loss_timeout_s"),
            Param("COM_OBL_RC_ACT", M.MAV_PARAM_TYPE_INT32, lambda: cfg.offboard_loss_action, self._set_loss_action),
            *ParamStore.settable(GF_ACTION=1, GF_MAX_HOR_DIST=0.0, GF_MAX_VER_DIST=0.0),  # PX4's: warns of no fence
            *ParamStore.constants(
                SYS_AUTOSTART=10016,
                MAV_SYS_ID=1,
                MAV_TYPE=2,
                SYS_HITL=0,
                NAV_DLL_ACT=0,
                COM_RC_IN_MODE=3,
                CAL_GYRO0_ID=1,
                CAL_ACC0_ID=1,
                CAL_MAG0_ID=1,
                COM_ARM_WO_GPS=0,
            ),
        ]

    def _land(self, cmd: Cmd) -> None:
        """NAV_LAND: LAND where the vehicle is. PX4 reads param 2 (precision) only in a mission: its Commander makes
        this a plain LAND (precision landing is its PRECLAND mode, DO_SET_MODE)."""
        self.v.guidance.land()

    def _set_loss_action(self, value: float) -> None:
        if int(value) in OFFBOARD_LOSS_ACTIONS:
            self.s.cfg.offboard_loss_action = int(value)
        else:
            kept = self.s.cfg.offboard_loss_action
            logger.info("SimVehicle: COM_OBL_RC_ACT %d is not simulated; keeping %d", value, kept)

    # ------------------------------------------------------------- commands
    def on_command(self, msg: mavlink.MAVLink_message) -> None:
        if msg.target_system not in (0, 1):
            return
        cmd = Cmd(msg)
        logger.debug("SimVehicle: %s", msg)
        handler = self._handlers.get(cmd.id)
        if handler is None:
            result = UNSUPPORTED
        else:
            try:
                result = handler(cmd)
            except CommandRefused as exc:
                result = TEMP_REJECTED if exc.temporary else DENIED
                self.s.status_text(M.MAV_SEVERITY_CRITICAL, f"Command refused: {exc}")
            except (ValueError, TypeError, OverflowError) as exc:
                result = M.MAV_RESULT_FAILED
                logger.warning("SimVehicle: command %d with bad parameters %s: %s", cmd.id, cmd.p, exc)
        logger.info(
            "SimVehicle: command %s -> %s",
            _name(M.enums["MAV_CMD"], cmd.id),
            _name(M.enums["MAV_RESULT"], result),
        )
        self.s.link.send(self.s.link.encoder.command_ack_encode(cmd.id, result, 0, 0, *cmd.src))
        for reply in self._after_ack:
            self.s.link.send(reply)
        self._after_ack.clear()

    def _mode_action(self, action: Callable[[Cmd], None]) -> Callable[[Cmd], int]:
        def run(cmd: Cmd) -> int:
            action(cmd)
            self.s.client_took_over()
            return ACCEPTED

        return run

    def _arm_disarm(self, cmd: Cmd) -> int:
        if cmd.p[0] >= 0.5:
            if self.v.mode == Mode.OFFBOARD and not self.s.setpoint_fresh():
                raise CommandRefused("offboard: no setpoints")
            self.v.arm()
        else:
            self.v.disarm(force=cmd.p[1] == FORCE_MAGIC)
        return ACCEPTED

    def _takeoff(self, cmd: Cmd) -> int:
        if self.s.dialect.takeoff_above_home:  # ArduCopter: metres above home, in GUIDED only
            if self.v.mode != Mode.GUIDED:
                raise CommandRefused(f"takeoff: not in GUIDED (in {self.v.mode})")
            alt = cmd.z if math.isfinite(cmd.z) else None
        else:
            alt = cmd.z - self.s.cfg.home.alt_m if math.isfinite(cmd.z) else None
        self.v.takeoff(alt)
        self.s.client_took_over()
        return ACCEPTED

    def _set_mode(self, cmd: Cmd) -> int:
        if not math.isfinite(cmd.p[0]) or not int(cmd.p[0]) & M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
            return DENIED
        modes = self.s.dialect.modes
        mode = modes.mode_from_command(int(cmd.p[1]), int(cmd.p[2]))
        g = self.v.guidance
        if mode is None or mode == Mode.ORBIT:
            return DENIED
        if mode != Mode.OFFBOARD and modes.custom_mode(mode) == modes.custom_mode(self.v.mode):
            pass  # already there: neither autopilot restarts the mode (ArduCopter's take-off is GUIDED)
        elif mode == Mode.OFFBOARD:
            if not self.s.setpoint_fresh():
                raise CommandRefused("offboard: no setpoints streaming")
            self.v.set_offboard(self.s.setpoint)
        elif mode == Mode.TAKEOFF:
            self.v.takeoff(None)
        elif mode in (Mode.LAND, Mode.PRECLAND):
            g.land(mode)
        elif mode == Mode.RTL:
            g.rtl()
        elif mode == Mode.GUIDED:
            g.guided()
        elif mode == Mode.LOITER:
            g.loiter()
        else:
            g.hold(mode)
        self.s.client_took_over()
        return ACCEPTED

    def _orbit(self, cmd: Cmd) -> int:
        if not self.v.in_air:
            raise CommandRefused("orbit: not in air")
        radius = cmd.p[0]
        if not math.isfinite(radius) or abs(radius) < 1.0:
            return DENIED
        speed = cmd.p[1] if math.isfinite(cmd.p[1]) else 1.0
        if radius < 0:
            speed = -speed
        north, east = float(self.v.pos[0]), float(self.v.pos[1])
        if cmd.x is not None and cmd.y is not None:
            north, east, _ = self.s.cfg.home.to_local(cmd.x, cmd.y, self.s.cfg.home.alt_m)
        down = self.s.cfg.home.alt_m - cmd.z if math.isfinite(cmd.z) else float(self.v.pos[2])
        self.v.guidance.orbit(Orbit(north, east, down, abs(radius), speed))
        self.s.client_took_over()
        return ACCEPTED

    def _reposition(self, cmd: Cmd) -> int:
        if not self.v.in_air:
            raise CommandRefused("reposition: not in air")
        home, pos = self.s.cfg.home, self.v.pos
        north, east = (
            home.to_local(cmd.x, cmd.y, home.alt_m)[:2]
            if cmd.x is not None and cmd.y is not None
            else (float(pos[0]), float(pos[1]))
        )
        down = home.alt_m - cmd.z if math.isfinite(cmd.z) else float(pos[2])
        speed = cmd.p[0] if math.isfinite(cmd.p[0]) and cmd.p[0] > 0 else None
        self.v.guidance.goto(north, east, min(down, 0.0), speed)
        self.s.client_took_over()
        return ACCEPTED

    def _change_speed(self, cmd: Cmd) -> int:
        if not math.isfinite(cmd.p[1]) or cmd.p[1] <= 0:
            return DENIED
        self.v.cfg.cruise_speed_ms = cmd.p[1]
        return ACCEPTED

    def _message_interval(self, cmd: Cmd) -> int:
        return ACCEPTED if self.s.streams.set_interval(int(cmd.p[0]), cmd.p[1]) else DENIED

    def _request_message(self, cmd: Cmd) -> int:
        msg_id = int(cmd.p[0])
        if not self.s.streams.can_build(msg_id):
            return UNSUPPORTED
        self._after_ack.append(self.s.streams.build(msg_id))
        return ACCEPTED

    def _gimbal_pitchyaw(self, cmd: Cmd) -> int:
        flags = int(cmd.p5) if math.isfinite(cmd.p5) else 0
        return self.s.gimbal.pitchyaw(cmd.p, flags, cmd.src, math.degrees(self.v.attitude()[2]))

    def _capabilities(self, cmd: Cmd) -> int:
        self._after_ack.append(self.s.streams.autopilot_version())
        return ACCEPTED

    # ----------------------------------------------------------- parameters
    def on_param(self, msg: mavlink.MAVLink_message) -> None:
        if msg.target_system not in (0, 1):
            return
        kind = msg.get_type()
        if kind == "PARAM_REQUEST_LIST":
            for index, param in self.params.all():
                self._send_param(index, param)
            return
        name = msg.param_id.rstrip("\x00") if isinstance(msg.param_id, str) else msg.param_id.decode()
        if kind == "PARAM_SET":
            found = self.params.set(name, msg.param_value)
        else:
            found = self.params.lookup(name, msg.param_index)
        if found is None:
            logger.info("SimVehicle: unknown parameter %r requested (PX4 stays silent)", name)
            return
        self._send_param(*found)

    def _send_param(self, index: int, param: Param) -> None:
        enc = self.s.link.encoder
        self.s.link.send(
            enc.param_value_encode(param.name.encode(), encode_value(param), param.kind, len(self.params), index)
        )


def _name(enum: dict, value: int) -> str:
    entry = enum.get(value)
    return entry.name if entry is not None else str(value)
