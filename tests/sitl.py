"""Real autopilot SITLs for tests marked ``sitl``: found, started, stopped; skipped with a reason when absent.

Build them with ``../shared/tools/build_sitl.sh`` (its header says how they are started, as here).
Binaries: ``$PX4_SITL_BIN`` / ``$ARDUCOPTER_SITL_BIN``, else under ``$SITL_DIR`` (default ``~/sitl``).
Each SITL listens on ports derived from an instance number; a free-looking instance is picked.
"""

from __future__ import annotations

import os
import random
import shutil
import signal
import socket
import subprocess
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

SITL_DIR = Path(os.environ.get("SITL_DIR", "~/sitl")).expanduser()
PX4_BIN = Path(os.environ.get("PX4_SITL_BIN", SITL_DIR / "px4/build/px4_sitl_default/bin/px4")).expanduser()
ARDUCOPTER_BIN = Path(os.environ.get("ARDUCOPTER_SITL_BIN", SITL_DIR / "ardupilot/build/sitl/bin/arducopter")
                      ).expanduser()
ARDUCOPTER_DEFAULTS = SITL_DIR / "ardupilot/Tools/autotest/default_params/copter.parm"


def require(binary: Path, variable: str) -> None:
    """Skip the test, saying how to get the SITL, when ``binary`` is not there."""
    if not os.access(binary, os.X_OK):
        pytest.skip(f"SITL not built: {binary} not found (run ../shared/tools/build_sitl.sh, or set {variable} "
                    "or SITL_DIR)")


def _port_free(port: int, kind: int) -> bool:
    with socket.socket(socket.AF_INET, kind) as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def _instance(ports_of: Callable[[int], tuple[int, ...]], kind: int, count: int) -> int:
    for instance in random.sample(range(count), count):
        if all(_port_free(port, kind) for port in ports_of(instance)):
            return instance
    pytest.skip("no free SITL instance ports")


@contextmanager
def _running(command: list[str], cwd: Path, env: dict[str, str] | None = None) -> Iterator[subprocess.Popen[bytes]]:
    log = (cwd / "sitl.log").open("wb")
    process = subprocess.Popen(command, cwd=cwd, env={**os.environ, **(env or {})}, stdout=log,
                               stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, start_new_session=True)
    try:
        yield process
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGTERM)
            try:
                process.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait()
        log.close()


@contextmanager
def px4_sitl(work: Path, params: dict[str, float] | None = None) -> Iterator[str]:
    """PX4 v1.16 SIH quad in ``work``, with ``params`` set at boot; yields the MAVSDK address of its offboard
    link (udpin, 14540 + i)."""
    require(PX4_BIN, "PX4_SITL_BIN")
    # PX4 sends to 14540 + i only for instances 0-9 (px4-rc.mavlink), from 14580 + i.
    instance = _instance(lambda i: (14540 + i, 14580 + i, 18570 + i), socket.SOCK_DGRAM, 10)
    etc = work / "etc"
    work.mkdir(parents=True, exist_ok=True)
    shutil.copytree(PX4_BIN.parent.parent / "etc", etc)
    env = {"PX4_SIM_MODEL": "sihsim_quadx", "PX4_SIMULATOR": "sihsim", "HEADLESS": "1", "PX4_SYS_AUTOSTART": "10040",
           **{f"PX4_PARAM_{name}": str(value) for name, value in (params or {}).items()}}
    with _running([str(PX4_BIN), "-i", str(instance), "-d", str(etc)], work, env):
        yield f"udpin://127.0.0.1:{14540 + instance}"


@contextmanager
def arducopter_sitl(work: Path, params: dict[str, float] | None = None) -> Iterator[str]:
    """ArduCopter 4.8 SITL quad in ``work``, with ``params`` as extra defaults; yields the MAVSDK address of its
    SERIAL0 (tcpout, 5760 + 10 i)."""
    require(ARDUCOPTER_BIN, "ARDUCOPTER_SITL_BIN")
    instance = _instance(lambda i: (5760 + 10 * i,), socket.SOCK_STREAM, 60)
    work.mkdir(parents=True, exist_ok=True)
    extra = work / "extra.parm"
    extra.write_text("".join(f"{name} {value}\n" for name, value in (params or {}).items()))
    command = [str(ARDUCOPTER_BIN), "--model", "quad", "--speedup", "1", "--defaults", f"{ARDUCOPTER_DEFAULTS},{extra}",
               "--home", "-35.363261,149.165230,584,353", "-I", str(instance), "--wipe", "--serial0", "tcp:0"]
    with _running(command, work):
        yield f"tcpout://127.0.0.1:{5760 + 10 * instance}"
