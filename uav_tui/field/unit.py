"""The systemd unit that starts the platform headless at boot: what it says, and where it goes.

Written for systemd 252 (Debian 12, Raspberry Pi OS bookworm). Its restarts back off by a fixed ``RestartSec``
and give up after ``StartLimitBurst`` starts within ``StartLimitIntervalSec``; growing delays (``RestartSteps``,
``RestartMaxDelaySec``) need systemd 254.
"""

from __future__ import annotations

import os
import shlex
import sys
from dataclasses import dataclass
from pathlib import Path

RESTART_SEC = 10
"""Seconds between a failed run and the next start (a camera or autopilot still booting gets time)."""
START_LIMIT_BURST = 10
START_LIMIT_INTERVAL_SEC = 600
"""More than ``START_LIMIT_BURST`` starts in this many seconds: the unit stays failed until ``reset-failed``."""
STOP_TIMEOUT_SEC = 30
"""How long SIGTERM (hold, then exit) may take before systemd kills the platform."""
SERIAL_GROUP = "dialout"
"""The group that owns serial ports on Debian and Raspberry Pi OS."""


@dataclass(frozen=True, slots=True)
class Unit:
    """One ``uav-tui`` service.

    Attributes:
        name: the unit's name without ``.service``.
        config: the absolute path of the ``uav.toml`` it runs.
        working_dir: where relative paths of the config (``runs_dir``, a processor's file) start.
        system: a system unit (starts at boot as ``user``) rather than a user unit (needs lingering).
        user: the account a system unit runs as.
    """

    name: str
    config: Path
    working_dir: Path
    system: bool
    user: str = ""

    @property
    def file_name(self) -> str:
        return f"{self.name}.service"

    def command(self) -> list[str]:
        """The platform's command line: headless, the named config, no ``--script`` (see docs/install.md)."""
        return [*platform_program(), "--no-ui", "--config", str(self.config)]

    def environment(self) -> dict[str, str]:
        """What the unit sets in the platform's environment (systemd adds PATH, and for a system unit HOME, USER)."""
        return {"PYTHONUNBUFFERED": "1"}

    def text(self) -> str:
        """The unit file."""
        service = [
            "Type=exec",
            f"ExecStart={' '.join(_quote(arg) for arg in self.command())}",
            f"WorkingDirectory={_path(self.working_dir)}",
            *(f"Environment={key}={value}" for key, value in self.environment().items()),
            "StandardInput=null",
            "StandardOutput=journal",
            "StandardError=journal",
            f"SyslogIdentifier={self.name}",
            "Restart=on-failure",
            f"RestartSec={RESTART_SEC}",
            "KillSignal=SIGTERM",
            "KillMode=mixed",
            f"TimeoutStopSec={STOP_TIMEOUT_SEC}",
        ]
        if self.system:
            service += [f"User={self.user}", f"SupplementaryGroups={SERIAL_GROUP}"]
        target = "multi-user.target" if self.system else "default.target"
        return "\n".join([
            f"# Written by `uav-tui service install`; remove with `uav-tui service remove --name {self.name}`.",
            "[Unit]",
            f"Description=uav-tui platform, headless ({_path(self.config)})",
            "After=network.target",
            f"StartLimitIntervalSec={START_LIMIT_INTERVAL_SEC}",
            f"StartLimitBurst={START_LIMIT_BURST}",
            "",
            "[Service]",
            *service,
            "",
            "[Install]",
            f"WantedBy={target}",
            "",
        ])


def platform_program() -> list[str]:
    """How to start this installation's platform: its ``uav-tui`` script beside the interpreter, else ``-m``."""
    script = Path(sys.executable).with_name("uav-tui")
    return [str(script)] if os.access(script, os.X_OK) else [sys.executable, "-m", "uav_tui"]


def default_unit_dir(system: bool) -> Path:
    """Where systemd reads units written by an administrator: system-wide, or the user's own."""
    if system:
        return Path("/etc/systemd/system")
    config_home = Path(os.environ.get("XDG_CONFIG_HOME") or Path.home() / ".config")
    return config_home / "systemd" / "user"


def _path(path: Path) -> str:
    """A path as a unit file's value: ``%`` doubled (systemd's specifiers); a line break refused (a new setting)."""
    text = str(path)
    if "\n" in text or "\r" in text:
        raise ValueError(f"{text!r}: a path with a line break cannot go in a unit file")
    return text.replace("%", "%%")


def _quote(arg: str) -> str:
    """One ExecStart word: quoted as a shell would, with systemd's ``%`` specifiers and ``$`` variables escaped."""
    return shlex.quote(arg).replace("%", "%%").replace("$", "$$")


def exec_start(text: str) -> list[str]:
    """The command line of a unit file's ``ExecStart=`` (empty when it has none)."""
    for line in text.splitlines():
        if line.startswith("ExecStart="):
            words = shlex.split(line.removeprefix("ExecStart="))
            return [word.replace("%%", "%").replace("$$", "$") for word in words]
    return []
