"""Launch helpers for the real autopilot SITLs (tests marked ``sitl``): PX4 SIH and ArduCopter.

Binaries (built by ``../shared/tools/build_sitl.sh``, see its header):

- PX4: ``$PX4_SITL_BIN``, else ``$SITL_DIR/px4/build/px4_sitl_default/bin/px4`` (``SITL_DIR`` = ``~/sitl``).
  SIH quad (``sihsim_quadx``): physics inside PX4, no Gazebo. Instance ``-i N`` talks to the
  offboard API on UDP 14540+N, so the ground side listens on ``udpin://127.0.0.1:14540+N``.
- ArduCopter: ``$ARDUCOPTER_SITL_BIN``, else ``$SITL_DIR/ardupilot/build/sitl/bin/arducopter``,
  ``--model quad`` (built-in physics). Instance ``-I N`` serves SERIAL0 on TCP 5760+10N:
  ``tcpout://127.0.0.1:5760+10N``.

Each helper picks the first instance number whose ports are free, runs the SITL in a scratch
folder with ``params`` set at boot, and stops it (SIGTERM, then SIGKILL) on exit. A test without
the binary is skipped and says which path it looked for.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from pymavlink import mavutil

SITL_DIR = Path(os.environ.get("SITL_DIR", Path.home() / "sitl")).expanduser()
PX4_BIN = Path(os.environ.get("PX4_SITL_BIN", SITL_DIR / "px4/build/px4_sitl_default/bin/px4")).expanduser()
ARDUCOPTER_BIN = Path(os.environ.get("ARDUCOPTER_SITL_BIN",
                                     SITL_DIR / "ardupilot/build/sitl/bin/arducopter")).expanduser()
ARDUCOPTER_HOME = "-35.363261,149.165230,584,353"
"""ArduPilot's usual SITL home (CMAC); its local origin is the world origin of the sim: camera."""

PX4_READY_S = 8.0
"""PX4 reports healthy ~5 s after boot."""
ARDUCOPTER_READY_S = 45.0
"""ArduCopter arms in GUIDED only ~40 s after boot (EKF position), although pre-arm flags look good earlier."""


@dataclass
class Sitl:
    """A running SITL: the connection string to give ``--fc`` and how long after boot it can arm."""

    name: str
    connection_string: str
    ready_after_s: float
    process: subprocess.Popen[bytes]
    log: Path

    def log_tail(self, chars: int = 2000) -> str:
        return self.log.read_text(errors="replace")[-chars:] if self.log.exists() else ""


def require(binary: Path, what: str) -> Path:
    """``binary``, or skip the test saying where it was looked for and how to build it."""
    if not binary.is_file() or not os.access(binary, os.X_OK):
        pytest.skip(f"{what} SITL not found at {binary}: build it with ../shared/tools/build_sitl.sh "
                    f"(or set {'PX4_SITL_BIN' if what == 'PX4' else 'ARDUCOPTER_SITL_BIN'} / SITL_DIR)")
    return binary


def port_free(port: int, kind: int) -> bool:
    with socket.socket(socket.AF_INET, kind) as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def free_instance(ports: list[tuple[int, int]], step: int, limit: int = 20) -> int:
    """The first instance ``i`` whose ``(base + step * i, kind)`` ports are all free."""
    for i in range(limit):
        if all(port_free(base + step * i, kind) for base, kind in ports):
            return i
    raise RuntimeError(f"no free SITL instance among {limit}: ports {ports} (+{step} per instance) all busy")


@contextlib.contextmanager
def running(name: str, command: list[str], cwd: Path, env: dict[str, str], connection_string: str,
            ready_after_s: float) -> Iterator[Sitl]:
    log = cwd / f"{name}.log"
    with log.open("wb") as out:
        process = subprocess.Popen(command, cwd=cwd, env={**os.environ, **env}, stdout=out, stderr=subprocess.STDOUT,
                                   stdin=subprocess.DEVNULL, start_new_session=True)
    sitl = Sitl(name, connection_string, ready_after_s, process, log)
    try:
        yield sitl
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGTERM)
            try:
                process.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait()


@contextlib.contextmanager
def px4_sih(workdir: Path, params: dict[str, float] | None = None) -> Iterator[Sitl]:
    """PX4 SITL with the SIH quad (``sihsim_quadx``), headless; the ground side listens on its UDP port."""
    binary = require(PX4_BIN, "PX4")
    instance = free_instance([(14540, socket.SOCK_DGRAM), (14580, socket.SOCK_DGRAM), (18570, socket.SOCK_DGRAM)],
                             step=1)
    shutil.copytree(binary.parents[1] / "etc", workdir / "etc")
    env = {"PX4_SIM_MODEL": "sihsim_quadx", "PX4_SIMULATOR": "sihsim", "HEADLESS": "1",
           "PX4_SYS_AUTOSTART": "10040", **{f"PX4_PARAM_{name}": str(value) for name, value in (params or {}).items()}}
    command = [str(binary), "-i", str(instance), "-d", str(workdir / "etc")]
    with running("px4", command, workdir, env, f"udpin://127.0.0.1:{14540 + instance}", PX4_READY_S) as sitl:
        yield sitl


@contextlib.contextmanager
def arducopter(workdir: Path, params: dict[str, float] | None = None) -> Iterator[Sitl]:
    """ArduCopter SITL, ``--model quad``; the ground side connects to its SERIAL0 TCP port."""
    binary = require(ARDUCOPTER_BIN, "ArduCopter")
    instance = free_instance([(5760, socket.SOCK_STREAM), (5762, socket.SOCK_STREAM), (5501, socket.SOCK_DGRAM)],
                             step=10)  # 5501+10N: the SITL's RC input
    extra = workdir / "extra.parm"
    extra.write_text("".join(f"{name} {value}\n" for name, value in (params or {}).items()))
    defaults = f"{binary.parents[3] / 'Tools/autotest/default_params/copter.parm'},{extra}"
    command = [str(binary), "--model", "quad", "--speedup", "1", "--defaults", defaults,
               "--home", ARDUCOPTER_HOME, "-I", str(instance), "--wipe", "--serial0", "tcp:0", "--serial1", "tcp:2"]
    port = 5760 + 10 * instance
    with running("arducopter", command, workdir, {}, f"tcpout://127.0.0.1:{port}", ARDUCOPTER_READY_S) as sitl:
        wait_listening(sitl, port + 2)  # SERIAL1, opened with SERIAL0: probing it leaves SERIAL0 to uav-tui
        yield sitl


def wait_listening(sitl: Sitl, port: int, timeout_s: float = 30.0) -> None:
    """Until the SITL accepts TCP connections on ``port`` (uav-tui connecting earlier would be refused)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and sitl.process.poll() is None:
        with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", port), timeout=1):
            return
        time.sleep(0.2)
    raise RuntimeError(f"{sitl.name} SITL not listening on TCP {port} after {timeout_s:g} s:\n{sitl.log_tail()}")


class SecondLink:
    """A second MAVLink client of the autopilot (system 1, component 1) on its own link, as an independent judge.

    Every second it sends a heartbeat (PX4 answers the last sender on its GCS port) and asks for ``stream`` at
    ``rate_hz`` (ArduCopter streams nothing until asked); each message of ``kinds`` from the autopilot goes to
    ``on_message``, on the link's own thread, until :meth:`close`.
    """

    def __init__(self, url: str, source_system: int, stream: str, kinds: list[str],
                 on_message: Callable[[Any], None], name: str, rate_hz: float = 10.0) -> None:
        self.link = mavutil.mavlink_connection(url, source_system=source_system)
        self._stream = getattr(mavutil.mavlink, f"MAVLINK_MSG_ID_{stream}")
        self._interval_us = round(1e6 / rate_hz)
        self._kinds, self._on_message = kinds, on_message
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._read, name=name, daemon=True)
        self._thread.start()

    def _ask(self) -> None:
        mav = self.link.mav
        mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS, mavutil.mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        mav.command_long_send(1, 1, mavutil.mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 0, self._stream, self._interval_us,
                              0, 0, 0, 0, 0)

    def _read(self) -> None:
        asked = 0.0
        while not self._stop.is_set():
            if time.monotonic() - asked > 1.0:
                self._ask()
                asked = time.monotonic()
            msg = self.link.recv_match(type=self._kinds, blocking=True, timeout=0.2)
            if msg is not None and msg.get_srcSystem() == 1 and msg.get_srcComponent() == 1:
                self._on_message(msg)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2)
        self.link.close()


def stop_uav_tui(process: subprocess.Popen[str]) -> None:
    """SIGTERM (the platform's safety exit: hold or land, then close), up to 30 s, then SIGKILL; nothing if it ended."""
    if process.poll() is None:
        process.send_signal(signal.SIGTERM)
        try:
            process.wait(30)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
