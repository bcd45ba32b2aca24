"""``doctor``'s check of the flight-controller link: a heartbeat within seconds, the autopilot's failsafe parameters
(the rules the platform applies at connect, :data:`controllers.failsafe.RULES`) and its GPS clock (SYSTEM_TIME).

It speaks MAVLink through pymavlink, not MAVSDK: a few messages, each wait bounded, and nothing is ever set.
"""

from __future__ import annotations

import asyncio
import errno
import struct
import time
from dataclasses import dataclass
from typing import Any

from controllers.autopilots import Autopilot
from controllers.connection import Connection, connection_failed, no_heartbeat_error
from controllers.failsafe import RULES, STALE_MARGIN_S, Context, Radio
from uav_tui.config import Config
from uav_tui.field.finding import Finding, fail, ok, warn

RC_RECEIVER = 0x10000
"""MAV_SYS_STATUS_SENSOR_RC_RECEIVER."""

PARAM_TIMEOUT_S = 2.0
"""Longest the answer to one parameter read may take."""
CLOCK_WAIT_S = 2.5
"""How long to wait for SYSTEM_TIME after the heartbeat (autopilots send it at 1 Hz or less)."""
_PX4, _ARDUPILOT = 12, 3
"""MAV_AUTOPILOT_PX4, MAV_AUTOPILOT_ARDUPILOTMEGA."""
_GCS, _INVALID = 6, 8
"""MAV_TYPE_GCS, MAV_AUTOPILOT_INVALID: heartbeats of ground stations and companions, not of an autopilot."""


@dataclass(slots=True)
class LinkReport:
    """What the link check found; ``gps_offset_ms`` (GPS UTC minus this clock) feeds the clock check."""

    findings: list[Finding]
    gps_offset_ms: int | None = None


def link(config: Config, connection: Connection, timeout_s: float) -> LinkReport:
    """Wait up to ``timeout_s`` for an autopilot's heartbeat on ``connection``; then read its failsafe and clock."""
    from pymavlink import mavutil

    address, options = _pymavlink_address(connection)
    try:
        mav = mavutil.mavlink_connection(address, source_system=254, retries=1, **options)
    except OSError as exc:
        reason = "BIND_ERROR" if exc.errno == errno.EADDRINUSE else (exc.strerror or str(exc))
        return LinkReport([fail("heartbeat", str(connection_failed(connection, reason)))])
    try:
        return _check(mav, config, connection, timeout_s)
    finally:
        mav.close()


def _pymavlink_address(connection: Connection) -> tuple[str, dict[str, Any]]:
    if connection.is_serial:
        return str(connection.device), {"baud": connection.baud}
    scheme = {"tcpout": "tcp"}.get(connection.scheme, connection.scheme)
    return f"{scheme}:{connection.host}:{connection.port}", {}


def _check(mav: Any, config: Config, connection: Connection, timeout_s: float) -> LinkReport:
    heartbeat = _wait(mav, ("HEARTBEAT",), timeout_s, lambda m: m.type != _GCS and m.autopilot != _INVALID)
    if heartbeat is None:
        error = asyncio.run(no_heartbeat_error(connection, timeout_s))
        return LinkReport([fail("heartbeat", str(error))])
    system, component = heartbeat.get_srcSystem(), heartbeat.get_srcComponent()
    autopilot = {_PX4: Autopilot.PX4, _ARDUPILOT: Autopilot.ARDUPILOT}.get(heartbeat.autopilot, Autopilot.UNKNOWN)
    report = LinkReport([ok("heartbeat", f"{autopilot.label}, system {system}, on {connection.url}")])
    report.findings += _failsafe(mav, config, autopilot, (system, component))
    clock = _wait(mav, ("SYSTEM_TIME",), CLOCK_WAIT_S, lambda m: m.get_srcSystem() == system)
    if clock is not None and clock.time_unix_usec > 0:
        report.gps_offset_ms = round(clock.time_unix_usec / 1000 - time.time_ns() / 1e6)
    return report


def _wait(mav: Any, types: tuple[str, ...], timeout_s: float, wanted: Any) -> Any:
    """The first message of ``types`` that is ``wanted`` within ``timeout_s``; our heartbeat goes out each second
    (an autopilot on a ``udpout`` link learns where to send only from it)."""
    deadline = time.monotonic() + timeout_s
    sent = -1.0
    while (left := deadline - time.monotonic()) > 0:
        if time.monotonic() - sent >= 1.0:
            mav.mav.heartbeat_send(_GCS, _INVALID, 0, 0, 0)
            sent = time.monotonic()
        message = mav.recv_match(type=list(types), blocking=True, timeout=min(left, 1.0))
        if message is not None and wanted(message):
            return message
    return None


def _failsafe(mav: Any, config: Config, autopilot: Autopilot, target: tuple[int, int]) -> list[Finding]:
    """The platform's failsafe rules on the values read (nothing set: ``tune_autopilot_failsafe`` does that)."""
    rules = RULES.get(autopilot)
    if rules is None:
        return [warn("failsafe", f"cannot check the offboard-loss failsafe of an {autopilot.label} "
                                 "(PX4 and ArduPilot are known): autonomy will be refused")]
    limit_s = config.safety.max_t + STALE_MARGIN_S
    tuned = config.safety.tune_autopilot_failsafe
    context = Context(limit_s, _radio(mav, target) if autopilot is Autopilot.PX4 else None)
    findings = []
    for param in rules:
        value = _read_param(mav, param.name, param.integer, target, bytewise=autopilot is Autopilot.PX4)
        if value is None:
            findings.append(warn("failsafe", f"{param.name} did not come within {PARAM_TIMEOUT_S:g} s: the "
                                             "platform reads it again at connect"))
        elif problem := param.problem(value, context):
            wanted = f"{param.safe_value(value, context):g}"
            if tuned:
                findings.append(warn("failsafe", f"{param.name} = {value:g} {problem}: uav-tui sets it to {wanted} "
                                                 "at connect (tune_autopilot_failsafe)"))
            else:
                findings.append(fail("failsafe", f"{param.name} = {value:g} {problem}: set {param.name} to {wanted} "
                                                 "(tune_autopilot_failsafe is off, so autonomy is refused)"))
        else:
            findings.append(ok("failsafe", f"{param.name} = {value:g}"))
    return findings


def _radio(mav: Any, target: tuple[int, int]) -> Radio:
    """PX4's radio as the platform judges it at connect: the RC receiver present in SYS_STATUS, COM_RC_IN_MODE."""
    status = _wait(mav, ("SYS_STATUS",), PARAM_TIMEOUT_S, lambda m: True)
    receiver = None if status is None else bool(status.onboard_control_sensors_present & RC_RECEIVER
                                                   and status.onboard_control_sensors_health & RC_RECEIVER)
    rc_in_mode = _read_param(mav, "COM_RC_IN_MODE", True, target, bytewise=True)
    return Radio(receiver, None if rc_in_mode is None else int(rc_in_mode))


def _read_param(mav: Any, name: str, integer: bool, target: tuple[int, int], *, bytewise: bool) -> float | None:
    """One PARAM_REQUEST_READ, bounded; PX4 carries an INT32 in the float's bytes (MAVSDK decodes it the same way)."""
    mav.mav.param_request_read_send(*target, name.encode(), -1)
    reply = _wait(mav, ("PARAM_VALUE",), PARAM_TIMEOUT_S, lambda m: m.param_id == name)
    if reply is None:
        return None
    if integer and bytewise:
        return float(struct.unpack("<i", struct.pack("<f", reply.param_value))[0])
    return float(reply.param_value)
