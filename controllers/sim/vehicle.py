"""The simulated vehicle process: physics at a fixed real-time step, MAVLink in and out, offboard
supervision (PX4's setpoint-stream rule and loss failsafe, ArduCopter's GUID_TIMEOUT) and the
ground-truth side channel."""

from __future__ import annotations

import logging
import math
import os
import threading
import time
from collections import deque
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import common as mavlink

from controllers.autopilots import Autopilot
from controllers.sim.commands import CommandHandler
from controllers.sim.dialect import DIALECTS
from controllers.sim.geo import Home
from controllers.sim.gimbal import SimGimbal
from controllers.sim.guidance import OFFBOARD_LOSS_ACTIONS, Mode, OffboardSetpoint, ThrottleStick
from controllers.sim.landing_target_reader import PadEstimate
from controllers.sim.link import MavlinkLink
from controllers.sim.missions import MissionStore
from controllers.sim.physics import Multicopter, PhysicsConfig
from controllers.sim.setpoints import SetpointRecord, parse_local_ned
from controllers.sim.streams import TelemetryStreams
from controllers.sim.truth_server import TruthServer

logger = logging.getLogger(__name__)


@dataclass(slots=True)
class ServerConfig:
    """Process-level options of the simulator (see ``python -m controllers.sim --help``)."""

    mavlink_port: int = 14540
    autopilot: Autopilot = Autopilot.PX4
    """The dialect spoken (:data:`controllers.sim.dialect.DIALECTS`): ``px4`` or ``ardupilot``."""
    truth_port: int = 14600
    home: Home = field(default_factory=Home)
    wind: tuple[float, float] = (0.0, 0.0)
    seed: int = 0
    rate_hz: float = 50.0
    offboard_loss_timeout_s: float = 1.0
    offboard_loss_action: int = 0
    """PX4's COM_OBL_RC_ACT: what the offboard-loss failsafe does (see :data:`OFFBOARD_LOSS_ACTIONS`)."""
    offboard_stream_window_s: float = 0.5
    failsafe_land_after_s: float = 10.0
    guided_timeout_s: float = 3.0
    """ArduCopter's GUID_TIMEOUT: a GUIDED velocity target older than this lapses into a hold (a position
    target does not)."""
    radio: bool = False
    """PX4 dialect: a radio connected and read (SYS_STATUS shows the RC receiver present; POSCTL is held)."""
    link_quality_pct: float | None = None
    """The RC receiver's signal in RC_CHANNELS, percent (None: no receiver, rssi unknown); the truth channel's
    ``link_quality`` changes it."""
    rc_throttle_pwm: int = 1000
    """ArduCopter dialect: the RC throttle input (SITL's default, the stick's minimum); LOITER follows it."""
    parent_pid: int | None = None
    """Exit when this process is no longer our parent (the launcher died without stopping us)."""
    gps_clock_offset_s: float = 0.0
    """The UTC time the vehicle sends (SYSTEM_TIME) minus this computer's clock."""
    precland_enabled: bool = False
    """ArduPilot dialect: PLND_ENABLED at start (precision landing from LANDING_TARGET in LAND)."""
    physics: PhysicsConfig = field(default_factory=PhysicsConfig)


class SimVehicleServer:
    """Owns the :class:`Multicopter` and everything that talks to it. One lock guards the state;
    the MAVLink reader and the truth channel run on their own threads, the physics on ``run``'s."""

    def __init__(self, config: ServerConfig) -> None:
        self.cfg = config
        self.lock = threading.RLock()
        self.dialect = DIALECTS[config.autopilot]
        self.vehicle = Multicopter(config.physics, wind=config.wind, seed=config.seed)
        self.vehicle.guidance.radio = config.radio
        if self.dialect.ardupilot:
            self.vehicle.guidance.stick = ThrottleStick(config.rc_throttle_pwm)
            self.vehicle.guidance.hold_mode = Mode.GUIDED
        self.link = MavlinkLink(config.mavlink_port)
        self.pad = PadEstimate(self.dialect.ardupilot)
        if self.dialect.ardupilot:
            self.pad.enabled = config.precland_enabled
            self.vehicle.guidance.precision_modes = frozenset({Mode.LAND})
        self.vehicle.guidance.pad = lambda: self.pad.pad(time.monotonic_ns())
        self.gimbal = SimGimbal()
        self.streams = TelemetryStreams(self.link.encoder, self.vehicle, config.home,
                                        gps_clock_offset_s=config.gps_clock_offset_s, dialect=self.dialect,
                                        gimbal=self.gimbal)
        self.streams.link_quality_pct = config.link_quality_pct
        self.commands = CommandHandler(self)
        self.missions = MissionStore(self.link.encoder)
        self.truth = TruthServer(self, config.truth_port)
        self.setpoint: OffboardSetpoint | None = None
        self.setpoint_ns = 0
        self.setpoint_log: deque[SetpointRecord] = deque(maxlen=20_000)
        self.failsafe_since_ns: int | None = None
        self._stop = threading.Event()
        self._peers: set[tuple[int, int]] = set()
        self._shown: tuple[Mode, bool] | None = None
        """(mode, armed) in the last tick: a change is announced by an extra HEARTBEAT at once."""

    # ------------------------------------------------------------- offboard
    def setpoint_fresh(self, now_ns: int | None = None) -> bool:
        """PX4 accepts OFFBOARD only while setpoints are streaming."""
        now_ns = time.monotonic_ns() if now_ns is None else now_ns
        window = self.cfg.offboard_stream_window_s * 1e9
        return self.setpoint is not None and now_ns - self.setpoint_ns <= window

    def client_took_over(self) -> None:
        """A command changed what the vehicle does: the offboard-loss failsafe is over."""
        self.failsafe_since_ns = None

    def _supervise_offboard(self, now_ns: int) -> None:
        v = self.vehicle
        if v.mode == Mode.GUIDED:
            sp = v.guidance.setpoint
            if sp is not None and sp.position is None and now_ns - self.setpoint_ns > self.cfg.guided_timeout_s * 1e9:
                v.guidance.guided()  # ArduCopter zeroes a lapsed velocity target: it stops and holds
            return
        if v.mode == Mode.OFFBOARD and v.armed:
            if now_ns - self.setpoint_ns > self.cfg.offboard_loss_timeout_s * 1e9:
                action = OFFBOARD_LOSS_ACTIONS[self.cfg.offboard_loss_action]
                getattr(v.guidance, action)()
                self.failsafe_since_ns = now_ns if action == "hold" else None
                self.status_text(mavlink.MAV_SEVERITY_WARNING, f"Failsafe: offboard setpoints lost, {action}")
            return
        if self.failsafe_since_ns is None:
            return
        if not v.armed or v.mode != Mode.HOLD:
            self.failsafe_since_ns = None
        elif now_ns - self.failsafe_since_ns > self.cfg.failsafe_land_after_s * 1e9:
            self.failsafe_since_ns = None
            v.guidance.land()
            self.status_text(mavlink.MAV_SEVERITY_WARNING, "Failsafe: no offboard client, landing")

    def status_text(self, severity: int, text: str) -> None:
        logger.info("SimVehicle: %s", text)
        self.link.send(self.link.encoder.statustext_encode(severity, text.encode()[:50]))

    # ------------------------------------------------------------- messages
    def _on_message(self, msg: mavlink.MAVLink_message, t_ns: int) -> None:
        kind = msg.get_type()
        if kind == "SET_POSITION_TARGET_LOCAL_NED":
            self._on_setpoint(msg, t_ns)
        elif kind == "LANDING_TARGET":
            self.pad.on_message(msg, t_ns, self.vehicle.pos.copy(), self.vehicle.attitude())
        elif kind == "GIMBAL_MANAGER_SET_ATTITUDE":
            self.gimbal.set_attitude(msg, math.degrees(self.vehicle.attitude()[2]))
        elif kind in ("COMMAND_LONG", "COMMAND_INT"):
            self.commands.on_command(msg)
        elif kind in ("PARAM_REQUEST_READ", "PARAM_REQUEST_LIST", "PARAM_SET"):
            self.commands.on_param(msg)
        elif kind in MissionStore.KINDS and getattr(msg, "target_system", 1) in (0, 1):
            for answer in self.missions.on_message(msg):
                self.link.send(answer)
        elif kind == "HEARTBEAT" and (msg.get_srcSystem(), msg.get_srcComponent()) not in self._peers:
            # greet a new ground station at once instead of making it wait up to a second
            self._peers.add((msg.get_srcSystem(), msg.get_srcComponent()))
            self.link.send(self.streams.heartbeat())
        elif kind == "PING" and msg.target_system == 0:
            enc = self.link.encoder
            self.link.send(enc.ping_encode(msg.time_usec, msg.seq, msg.get_srcSystem(), msg.get_srcComponent()))
        elif kind not in ("HEARTBEAT", "TIMESYNC", "SYSTEM_TIME"):
            logger.debug("SimVehicle: ignoring %s", kind)

    def _on_setpoint(self, msg: mavlink.MAVLink_message, t_ns: int) -> None:
        if msg.target_system not in (0, 1):
            return
        record, setpoint = parse_local_ned(msg, t_ns, self.vehicle)
        self.setpoint_log.append(record)
        if setpoint is None:
            return
        self.setpoint, self.setpoint_ns = setpoint, t_ns
        if self.vehicle.mode == Mode.OFFBOARD:
            self.vehicle.guidance.offboard(setpoint)
        elif self.dialect.ardupilot and self.vehicle.mode in (Mode.GUIDED, Mode.TAKEOFF):  # in_guided_mode()
            self.vehicle.guidance.follow(setpoint)

    def _reader(self) -> None:
        while not self._stop.is_set():
            msgs, t_ns = self.link.receive()
            for msg in msgs:
                try:
                    with self.lock:
                        self._on_message(msg, t_ns)
                except Exception:
                    logger.exception("SimVehicle: failed to handle %s", msg.get_type())

    # ----------------------------------------------------------------- loop
    def stop(self) -> None:
        self._stop.set()

    def run(self) -> None:
        """Serve until :meth:`stop`; returns after closing the sockets."""
        threads = [
            threading.Thread(target=self._reader, name="sim-mavlink-rx", daemon=True),
            threading.Thread(target=self.truth.serve, args=(self._stop,), name="sim-truth", daemon=True),
        ]
        for t in threads:
            t.start()
        dt = 1.0 / self.cfg.rate_hz
        next_tick = time.monotonic()
        try:
            while not self._stop.is_set():
                now = time.monotonic()
                steps = 0
                while next_tick <= now and steps < 5:
                    with self.lock:
                        self.vehicle.step(dt)
                        self.gimbal.step(dt)
                    next_tick += dt
                    steps += 1
                if next_tick <= now:
                    next_tick = now + dt
                self._publish(now)
                if self.cfg.parent_pid is not None and os.getppid() != self.cfg.parent_pid:
                    logger.warning("SimVehicle: parent process %d is gone; exiting", self.cfg.parent_pid)
                    break
                self._stop.wait(max(0.0, next_tick - time.monotonic()))
        finally:
            self._stop.set()
            self.link.wake()
            self.truth.wake()
            for t in threads:
                t.join(timeout=1.0)
            self.link.close()
            self.truth.close()

    def _publish(self, now: float) -> None:
        """Once per tick: failsafes, announcements, due telemetry, the truth datagram."""
        with self.lock:
            self._supervise_offboard(time.monotonic_ns())
            for text in self.vehicle.events:
                self.status_text(mavlink.MAV_SEVERITY_INFO, text)
            self.vehicle.events.clear()
            due = self.streams.due(now)
            shown = (self.vehicle.mode, self.vehicle.armed)
            if shown != self._shown and not any(m.get_msgId() == mavlink.MAVLINK_MSG_ID_HEARTBEAT for m in due):
                due.append(self.streams.heartbeat())
            self._shown = shown
            truth = self.truth.snapshot() if self.truth.has_subscribers else None
        for msg in due:
            self.link.send(msg)
        if truth is not None:
            self.truth.publish(truth)

    def describe(self) -> str:
        h = self.cfg.home
        return (
            f"sim vehicle ready: mavlink udpout 127.0.0.1:{self.cfg.mavlink_port} "
            f"(connect with udpin://127.0.0.1:{self.cfg.mavlink_port}), truth udp 127.0.0.1:{self.truth.port}, "
            f"home {h.lat_deg:.6f},{h.lon_deg:.6f},{h.alt_m:.1f}, wind {self.cfg.wind}"
        )
