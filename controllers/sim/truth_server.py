"""The simulator's side of the ground-truth channel (protocol in :mod:`controllers.sim`)."""

from __future__ import annotations

import contextlib
import json
import logging
import math
import socket
import threading
import time
from typing import TYPE_CHECKING, Any

from controllers.sim.guidance import Mode
from controllers.sim.physics import Multicopter

if TYPE_CHECKING:
    from controllers.sim.vehicle import SimVehicleServer

logger = logging.getLogger(__name__)

MAX_SUBSCRIBERS = 16
MAX_SETPOINT_RECORDS = 400
"""Per reply, so one datagram stays well under 64 KiB; ask again with a later since_mono_ns."""


def truth_dict(v: Multicopter, server: SimVehicleServer) -> dict[str, Any]:
    roll, pitch, yaw = v.attitude()
    lat, lon, alt = server.cfg.home.to_global(*v.pos)
    n, e, d = (float(x) for x in v.pos)
    vn, ve, vd = (float(x) for x in v.vel)
    return {
        "t_mono_ns": time.monotonic_ns(),
        "t_wall_ns": time.time_ns(),
        "time_boot_ms": server.streams.boot_ms(),
        "n": n,
        "e": e,
        "d": d,
        "vn": vn,
        "ve": ve,
        "vd": vd,
        "roll": math.degrees(roll),
        "pitch": math.degrees(pitch),
        "yaw": math.degrees(yaw),
        "armed": v.armed,
        "mode": str(v.mode),
        "in_air": v.in_air,
        "lat": lat,
        "lon": lon,
        "alt": alt,
        "battery": v.battery,
        "wind_n": float(v.wind[0]),
        "wind_e": float(v.wind[1]),
        "rc_throttle": v.guidance.stick.pwm if v.guidance.stick is not None else None,
        "link_quality": server.streams.link_quality_pct,
        **server.gimbal.truth(),
    }


def teleport(v: Multicopter, north: float, east: float, down: float, yaw_deg: float | None) -> None:
    """Move the vehicle (tests only): zero velocity, hold the new point if holding."""
    v.pos[:] = (north, east, min(down, 0.0))
    v.vel[:] = 0.0
    if yaw_deg is not None:
        v.yaw = math.radians(yaw_deg)
    v.in_air = bool(v.pos[2] < -0.1)
    if v.mode in (Mode.HOLD, Mode.POSCTL, Mode.MANUAL, Mode.LOITER, Mode.GUIDED):
        v.guidance.hold(v.mode)


RC_MODES = {
    "POSCTL": lambda guidance: guidance.hold(Mode.POSCTL),
    "HOLD": lambda guidance: guidance.hold(),
    "RTL": lambda guidance: guidance.rtl(),
    "LAND": lambda guidance: guidance.land(),
    "LOITER": lambda guidance: guidance.loiter(),
}
"""Modes an RC pilot (or an onboard failsafe) can switch to behind the ground station's back."""


class TruthServer:
    """UDP JSON on 127.0.0.1:port: subscriptions, 50 Hz truth datagrams and control requests."""

    def __init__(self, server: SimVehicleServer, port: int) -> None:
        self.s = server
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self.sock.bind(("127.0.0.1", port))
        except OSError as exc:
            self.sock.close()
            raise OSError(exc.errno, f"cannot open the truth port {port}: {exc.strerror}") from exc
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self._subscribers: dict[tuple[str, int], None] = {}
        self._sub_lock = threading.Lock()

    @property
    def has_subscribers(self) -> bool:
        return bool(self._subscribers)

    def snapshot(self) -> dict[str, Any]:
        """Truth now (the caller holds the server lock)."""
        return truth_dict(self.s.vehicle, self.s)

    def publish(self, truth: dict[str, Any]) -> None:
        with self._sub_lock:
            targets = list(self._subscribers)
        if not targets:
            return
        data = json.dumps(truth).encode()
        for addr in targets:
            try:
                self.sock.sendto(data, addr)
            except OSError:
                with self._sub_lock:
                    self._subscribers.pop(addr, None)

    def serve(self, stop: threading.Event) -> None:
        while not stop.is_set():
            try:
                data, addr = self.sock.recvfrom(65535)
            except (TimeoutError, OSError):
                continue
            if not data:
                continue
            request: Any = None
            try:
                request = json.loads(data)
                reply = self.handle(request, addr)
            except Exception as exc:
                reply = {"ok": False, "error": f"{type(exc).__name__}: {exc}"}
            if isinstance(request, dict) and "id" in request:
                reply["id"] = request["id"]
            try:
                self.sock.sendto(json.dumps(reply).encode(), addr)
            except OSError as exc:
                logger.debug("TruthServer: reply to %s failed: %s", addr, exc)

    def handle(self, req: dict[str, Any], addr: tuple[str, int]) -> dict[str, Any]:
        cmd = req.get("cmd")
        s, v = self.s, self.s.vehicle
        if cmd == "subscribe":
            with self._sub_lock:
                if len(self._subscribers) >= MAX_SUBSCRIBERS and addr not in self._subscribers:
                    self._subscribers.pop(next(iter(self._subscribers)))
                self._subscribers[addr] = None
            return {"ok": True, "cmd": "subscribe"}
        if cmd == "unsubscribe":
            with self._sub_lock:
                self._subscribers.pop(addr, None)
            return {"ok": True, "cmd": "unsubscribe"}
        with s.lock:
            if cmd == "state":
                return {"ok": True, "cmd": "state", "state": self.snapshot()}
            if cmd == "set_wind":
                v.wind[:2] = (float(req.get("n", 0.0)), float(req.get("e", 0.0)))
                return {"ok": True, "cmd": "set_wind"}
            if cmd == "teleport":
                teleport(
                    v,
                    float(req.get("n", v.pos[0])),
                    float(req.get("e", v.pos[1])),
                    float(req.get("d", v.pos[2])),
                    req.get("yaw"),
                )
                return {"ok": True, "cmd": "teleport", "state": self.snapshot()}
            if cmd == "rc_mode":  # the pilot flips the RC mode switch: no MAVLink client is involved
                RC_MODES[str(req.get("mode"))](v.guidance)
                return {"ok": True, "cmd": "rc_mode", "state": self.snapshot()}
            if cmd == "rc_throttle":  # the pilot moves the throttle stick (ArduCopter dialect)
                if v.guidance.stick is None:
                    return {"ok": False, "error": "rc_throttle: no RC in the px4 dialect (--autopilot ardupilot)"}
                pwm = int(req.get("pwm", 1000))
                if not 800 <= pwm <= 2200:
                    return {"ok": False, "error": f"rc_throttle: pwm {pwm} outside 800..2200"}
                v.guidance.stick.pwm = pwm
                return {"ok": True, "cmd": "rc_throttle", "state": self.snapshot()}
            if cmd == "link_quality":  # the RC signal fades (a percentage) or its receiver goes (null: unknown)
                pct = req.get("pct")
                s.streams.link_quality_pct = None if pct is None else float(pct)
                return {"ok": True, "cmd": "link_quality"}
            if cmd == "stream":  # a sensor or a stream stops (interval_us -1) or comes back (0: its default rate)
                known = s.streams.set_interval(int(req.get("msg_id", -1)), float(req.get("interval_us", 0)))
                return {"ok": known, "cmd": "stream"} if known else {"ok": False, "error": "stream: unknown msg_id"}
            if cmd in ("setpoints", "landing_targets"):
                since = int(req.get("since_mono_ns", 0))
                log = s.setpoint_log if cmd == "setpoints" else s.pad.log
                records = [r.as_dict() for r in log if r.t_mono_ns > since]
                more = len(records) > MAX_SETPOINT_RECORDS
                return {
                    "ok": True,
                    "cmd": cmd,
                    "records": records[:MAX_SETPOINT_RECORDS],
                    "more": more,
                }
        return {"ok": False, "error": f"unknown cmd {cmd!r}"}

    def wake(self) -> None:
        """Unblock :meth:`serve` waiting for a request."""
        with contextlib.suppress(OSError):
            self.sock.sendto(b"", self.sock.getsockname())

    def close(self) -> None:
        self.sock.close()
