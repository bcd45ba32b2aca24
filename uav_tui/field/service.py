"""``uav-tui service install|remove|status``: the platform as a systemd service that starts headless at boot.

The unit (:mod:`~uav_tui.field.unit`) runs ``uav-tui --no-ui --config PATH`` and nothing else: no ``--script``,
so at boot the vehicle is only connected to, never armed or flown, and autonomy starts off as in every run.
"""

from __future__ import annotations

import argparse
import getpass
import os
import re
import shlex
import sys
from pathlib import Path

from uav_tui.arguments import ArgumentParser
from uav_tui.config import find_config_file, load_config
from uav_tui.errors import CONFIG_ERRORS, ConfigError, error_line
from uav_tui.field.tools import run_tool
from uav_tui.field.unit import Unit, default_unit_dir, exec_start
from uav_tui.output.text import safe

SYSTEMCTL_TIMEOUT_S = 20.0
"""Longest a ``systemctl`` step may take (``daemon-reload`` on a Pi's SD card can be slow)."""
JOURNAL_LINES = 10
"""Lines of the journal ``status`` shows."""
PROG = "uav-tui service"
UNIT_NAME = re.compile(r"[A-Za-z0-9:_.\-]{1,200}")


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(prog=PROG, description="Start the platform headless at boot (a systemd unit).")
    actions = parser.add_subparsers(dest="action", required=True, metavar="install|remove|status")
    for name, text in (("install", "write the unit, reload systemd and enable it"),
                       ("remove", "disable and stop the unit, delete it"),
                       ("status", "installed? enabled? running? and its last journal lines")):
        action = actions.add_parser(name, help=text, description=text)
        action.add_argument("--name", default="uav-tui", type=_unit_name,
                            help="the unit's name: letters, digits, - _ . : (default: uav-tui)")
        action.add_argument("--system", action="store_true",
                            help="a system unit (root writes it; runs as --run-as) instead of your user's unit")
        action.add_argument("--unit-dir", metavar="DIR", help="where the unit file goes (default: systemd's folder)")
        if name != "status":
            action.add_argument("--no-systemctl", action="store_true",
                                help="only write / delete the file; print the systemctl commands to run")
    install = actions.choices["install"]
    install.add_argument("--config", metavar="PATH",
                         help="the uav.toml to run (default: the one uav-tui would find here)")
    install.add_argument("--run-as", metavar="USER", help="with --system: the account (default: $SUDO_USER)")
    install.add_argument("--working-dir", metavar="DIR",
                         help="where the config's relative paths start (runs_dir...); default: this folder")
    return parser


def _unit_name(text: str) -> str:
    """A systemd unit name (no folder, nothing systemd reads as a specifier or a new line)."""
    if not UNIT_NAME.fullmatch(text) or text.startswith("."):
        raise argparse.ArgumentTypeError(f"{text!r} is not a unit name: use letters, digits and - _ . :")
    return text


def main(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    unit_dir = Path(args.unit_dir).expanduser() if args.unit_dir else default_unit_dir(args.system)
    path = unit_dir / f"{args.name}.service"
    if args.action == "status":
        return _status(args, path)
    if args.action == "remove":
        return _remove(args, path)
    try:
        unit = _unit(args)
    except CONFIG_ERRORS as exc:
        print(safe(error_line(exc, PROG), multiline=True), file=sys.stderr)
        return 2
    try:
        unit_dir.mkdir(parents=True, exist_ok=True)
        path.write_text(unit.text(), encoding="utf-8")
    except OSError as exc:
        hint = " (a system unit: run with sudo)" if args.system else ""
        print(error_line(f"cannot write {path}: {exc.strerror or exc}{hint}", PROG), file=sys.stderr)
        return 2
    print(f"wrote {path}: runs {shlex.join(unit.command())} in {unit.working_dir}")
    steps = [["daemon-reload"], ["enable", unit.file_name]]
    done = not args.no_systemctl and _systemctl_steps(args.system, steps)
    if not done:
        print("to enable it: " + "; ".join(_command_text(args.system, step) for step in steps))
    print(f"start it now: {_command_text(args.system, ['start', unit.file_name])}; "
          f"its log: journalctl {_journal_scope(args.system)}-u {unit.name} -f")
    if not args.system:
        print(_linger_advice(getpass.getuser()) or "lingering is on: the unit starts at boot")
    return 0


def _unit(args: argparse.Namespace) -> Unit:
    config = find_config_file(args.config)
    if config is None:
        raise ConfigError("no uav.toml here: name the config the service runs with --config PATH",
                               key="config")
    load_config(config)  # a config that would not start is refused now, not at every boot
    user = args.run_as or os.environ.get("SUDO_USER") or getpass.getuser()
    if args.system and not args.run_as and user == "root":
        raise ConfigError("a system unit runs as a user, not root: name it with --run-as USER", key="run-as")
    working_dir = Path(args.working_dir or ".").expanduser().resolve()
    return Unit(args.name, config.resolve(), working_dir, args.system, user)


def _remove(args: argparse.Namespace, path: Path) -> int:
    steps = [["disable", "--now", path.name]]
    if args.no_systemctl or not _systemctl_steps(args.system, steps):
        print(f"to stop and disable it: {_command_text(args.system, steps[0])}")
    try:
        path.unlink()
    except FileNotFoundError:
        print(f"{path} is not installed")
        return 1
    except OSError as exc:
        print(error_line(f"cannot delete {path}: {exc.strerror or exc}", PROG), file=sys.stderr)
        return 2
    print(f"deleted {path}")
    if args.no_systemctl or not _systemctl_steps(args.system, [["daemon-reload"]]):
        print(f"then: {_command_text(args.system, ['daemon-reload'])}")
    return 0


def _status(args: argparse.Namespace, path: Path) -> int:
    if not path.is_file():
        print(f"not installed: no {path} (uav-tui service install --config PATH)")
        return 1
    print(f"installed: {path}")
    print(f"runs: {shlex.join(exec_start(path.read_text(encoding='utf-8')))}")
    for question in ("is-enabled", "is-active"):
        ok, output = run_tool("systemctl", *_scope(args.system), question, path.name)
        print(f"{question.removeprefix('is-')}: {_one_line(output) or '?'}")
    if not args.system:
        print(_linger_advice(getpass.getuser()) or "lingering: on (starts at boot)")
    ok, output = run_tool("journalctl", *_scope(args.system), "-u", args.name, "-n", str(JOURNAL_LINES),
                          "--no-pager", "-o", "short-iso")
    if ok and output.strip():
        print("last journal lines:\n" + safe(output.rstrip(), multiline=True))
    else:
        print(f"no journal lines ({_one_line(output) or 'journalctl gave none'})")
    return 0


def _linger_advice(user: str) -> str:
    """What to do so ``user``'s units start at boot; "" when lingering is on."""
    ok, output = run_tool("loginctl", "show-user", user, "--property=Linger", "--value")
    if ok and output.strip() == "yes":
        return ""
    return (f"a user unit starts at boot only with lingering (now: {_one_line(output) or 'unknown'}): "
            f"sudo loginctl enable-linger {user}; or install a system unit (--system)")


def _systemctl_steps(system: bool, steps: list[list[str]]) -> bool:
    """Run ``systemctl`` steps in order; False (having said why) at the first that fails."""
    for step in steps:
        ok, output = run_tool("systemctl", *_scope(system), *step, timeout_s=SYSTEMCTL_TIMEOUT_S)
        if not ok:
            print(f"{_command_text(system, step)} failed: {_one_line(output)}")
            return False
    return True


def _one_line(output: str) -> str:
    return safe(" ".join(output.split()))


def _scope(system: bool) -> list[str]:
    return [] if system else ["--user"]


def _journal_scope(system: bool) -> str:
    return "" if system else "--user "


def _command_text(system: bool, step: list[str]) -> str:
    return ("sudo systemctl " if system else "systemctl --user ") + " ".join(step)
