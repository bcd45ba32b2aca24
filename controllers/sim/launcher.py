"""Start and stop the simulated vehicle as a child process (used by ``--fc sim`` and the tests)."""

from __future__ import annotations

import contextlib
import logging
import os
import random
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

from controllers.autopilots import Autopilot
from controllers.errors import ControllerError
from controllers.sim.geo import Home
from controllers.sim.truth import TruthClient

logger = logging.getLogger(__name__)

REPO_ROOT = Path(__file__).resolve().parents[2]
"""Put on the child's PYTHONPATH so the simulator runs without the package being installed."""


EPHEMERAL_PORTS = Path("/proc/sys/net/ipv4/ip_local_port_range")
LOWEST_PORT = 20000
"""Ports are picked from here up to the start of the kernel's ephemeral range (above MAVLink's 14540-14580,
5760 and RTSP's 8554, which a ground station or camera on the same machine may bind later)."""


def _ephemeral_range_start() -> int:
    with contextlib.suppress(OSError, ValueError):
        return int(EPHEMERAL_PORTS.read_text().split()[0])
    return 32768  # Linux's default; macOS's range starts higher still


def free_ports(count: int, kind: socket.SocketKind = socket.SOCK_DGRAM) -> list[int]:
    """``count`` distinct ports (UDP by default) on 127.0.0.1, free now, below the kernel's ephemeral range.

    A port from ``bind(0)`` is in that range, so once released the kernel may hand it to any socket
    bound to port 0 (the simulator's own, MAVSDK's, another test's) before its user binds it again:
    a rare ``Address already in use``. Ports below the range are only ever taken by explicit binds.
    """
    candidates = range(LOWEST_PORT, _ephemeral_range_start())
    chosen: list[socket.socket] = []
    try:
        for port in random.sample(candidates, len(candidates)):
            sock = socket.socket(socket.AF_INET, kind)
            try:
                sock.bind(("127.0.0.1", port))
            except OSError:
                sock.close()
                continue
            chosen.append(sock)
            if len(chosen) == count:
                return [s.getsockname()[1] for s in chosen]
        raise OSError(f"no {count} free ports from {candidates.start} up to the ephemeral range ({EPHEMERAL_PORTS})")
    finally:
        for sock in chosen:
            sock.close()


def free_udp_port() -> int:
    """A UDP port on 127.0.0.1 that is free now and that no ``bind(0)`` can take (see :func:`free_ports`)."""
    return free_ports(1)[0]


START_TIMEOUT_S = 30.0
"""How long a simulator may take to answer after its spawn: over 10 s was seen on two cores at load 20 (its
imports); a process that exits is reported at once."""


class SimVehicle:
    """The simulator process on its own free ports.

    Example::

        with SimVehicle(wind=(2.0, 0.0)) as sim:
            await mavsdk.add_any_connection(sim.connection_string)
            truth = sim.truth().latest()

    Args:
        home: where the vehicle boots (default: PX4 SITL's Zurich home).
        wind: steady wind (north, east) in m/s.
        seed: random seed for the noise.
        noise: add sensor noise to the telemetry.
        extra_args: more ``python -m controllers.sim`` options, e.g. ``("--rtl-alt", "20")``.
        autopilot: the dialect it speaks, PX4 or ArduPilot (see :mod:`controllers.sim.dialect`).
    """

    def __init__(
        self,
        home: Home | tuple[float, float, float] | None = None,
        wind: tuple[float, float] | None = None,
        seed: int = 0,
        extra_args: Sequence[str] = (),
        noise: bool = False,
        autopilot: Autopilot = Autopilot.PX4,
    ) -> None:
        self.home = Home(*home) if isinstance(home, tuple) else (home or Home())
        self.wind = wind or (0.0, 0.0)
        self.seed = seed
        self.extra_args = (*(("--noise",) if noise else ()), "--autopilot", autopilot, *extra_args)
        self.mavlink_port = 0
        self.truth_port = 0
        self._proc: subprocess.Popen[bytes] | None = None
        self._log_path: Path | None = None
        self._clients: list[TruthClient] = []

    @property
    def connection_string(self) -> str:
        """The MAVSDK address that reaches this vehicle."""
        return f"udpin://127.0.0.1:{self.mavlink_port}"

    @property
    def pid(self) -> int | None:
        return self._proc.pid if self._proc else None

    @property
    def running(self) -> bool:
        return self._proc is not None and self._proc.poll() is None

    def exit_status(self) -> str | None:
        """How the process ended by itself (``"killed by SIGKILL"``, ``"exited with code 1"``), else None.

        None while it runs and after :meth:`stop` (an exit asked for is not a death).
        """
        code = self._proc.poll() if self._proc is not None else None
        if code is None:
            return None
        if code < 0:
            with contextlib.suppress(ValueError):
                return f"killed by {signal.Signals(-code).name}"
            return f"killed by signal {-code}"
        return f"exited with code {code}"

    def command(self) -> list[str]:
        h = self.home
        return [
            sys.executable,
            "-m",
            "controllers.sim",
            "--mavlink-port",
            str(self.mavlink_port),
            "--truth-port",
            str(self.truth_port),
            "--home",
            f"{h.lat_deg},{h.lon_deg},{h.alt_m}",
            "--wind",
            f"{self.wind[0]},{self.wind[1]}",
            "--seed",
            str(self.seed),
            "--parent-pid",
            str(os.getpid()),
            *self.extra_args,
        ]

    def start(self, timeout: float = START_TIMEOUT_S) -> SimVehicle:
        """Spawn the process and wait until its truth channel answers.

        Raises:
            ControllerError: the process exited or did not answer within ``timeout`` (its log is quoted).
        """
        if self.running:
            return self
        self.mavlink_port, self.truth_port = free_ports(2)
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(REPO_ROOT), env.get("PYTHONPATH")]))
        fd, log_name = tempfile.mkstemp(prefix="uav-sim-", suffix=".log")
        self._log_path = Path(log_name)
        with os.fdopen(fd, "wb") as log:
            self._proc = subprocess.Popen(
                self.command(),
                env=env,
                stdout=log,
                stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL,
                cwd=REPO_ROOT,
                process_group=0,  # like a real autopilot, it outlives a hang-up until it is stopped
            )
        deadline = time.monotonic() + timeout
        with TruthClient(self.truth_port, subscribe=False) as probe:
            while time.monotonic() < deadline:
                if self._proc.poll() is not None:
                    break
                try:
                    probe.request({"cmd": "state"}, timeout=0.3)
                except TimeoutError:
                    continue
                logger.info(
                    "SimVehicle(pid %s) up: mavlink %d, truth %d",
                    self.pid,
                    self.mavlink_port,
                    self.truth_port,
                )
                return self
        output = self.log_text()
        self.stop()
        raise ControllerError(f"simulated vehicle did not start within {timeout} s; its output:\n{output[-2000:]}")

    def log_text(self) -> str:
        """What the simulator printed so far (stdout and stderr)."""
        if self._log_path is None or not self._log_path.exists():
            return ""
        return self._log_path.read_text(errors="replace")

    def truth(self, subscribe: bool = True) -> TruthClient:
        """A new client of the truth channel; closed by :meth:`stop` if still open."""
        client = TruthClient(self.truth_port, subscribe=subscribe)
        self._clients.append(client)
        return client

    def stop(self, timeout: float = 5.0) -> int | None:
        """SIGTERM, wait, then SIGKILL; idempotent. Returns the exit code (None if never started)."""
        for client in self._clients:
            client.close()
        self._clients.clear()
        proc, self._proc = self._proc, None
        code = None
        if proc is not None:
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
                try:
                    proc.wait(timeout)
                except subprocess.TimeoutExpired:
                    logger.warning("SimVehicle(pid %s) ignored SIGTERM; killing it", proc.pid)
                    proc.kill()
                    proc.wait()
            code = proc.returncode
        if self._log_path is not None:
            self._log_path.unlink(missing_ok=True)
            self._log_path = None
        return code

    def __enter__(self) -> SimVehicle:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
