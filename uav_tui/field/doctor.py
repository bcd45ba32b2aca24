"""``uav-tui doctor``: what a field setup gets wrong, one line per check (OK, WARN, FAIL) with what to do.

Exit status: 0 flyable (warnings allowed), 1 a FAIL blocks flight, 2 bad usage or a configuration that does not
load. Every check is bounded in time: the heartbeat by ``--heartbeat-timeout``, each tool and probe by seconds.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from controllers.connection import parse_connection
from controllers.errors import ConnectError
from uav_tui.arguments import ArgumentParser
from uav_tui.config import Config, add_config_flags, find_config_file, overrides_from_args
from uav_tui.config.loading import config_from_data, read_config_data
from uav_tui.errors import CONFIG_ERRORS, error_line
from uav_tui.field import check_devices, check_host, check_link
from uav_tui.field.finding import Finding, Level, fail, ok
from uav_tui.output.text import safe
from uav_tui.token_strength import token_problem

PROG = "uav-tui doctor"
EXIT_FLYABLE, EXIT_BLOCKED, EXIT_USAGE = 0, 1, 2


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(prog=PROG, description=(
        "Check this drone's setup: cameras, serial port, autopilot link and failsafe, clock, disk, models, CPU, "
        "web token. One line per check: OK, WARN (flyable, but fix it) or FAIL (blocks flight), with what to do. "
        "Exit status: 0 flyable, 1 something blocks flight, 2 bad usage or configuration."))
    parser.add_argument("--config", metavar="PATH", help="the uav.toml to check (default: the one uav-tui finds)")
    parser.add_argument("--heartbeat-timeout", type=float, default=5.0, metavar="S",
                        help="how long to wait for the autopilot's heartbeat (default 5)")
    add_config_flags(parser)
    return parser


def main(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    if not 0.5 <= args.heartbeat_timeout <= 60:
        print(error_line("--heartbeat-timeout must be 0.5 to 60 s", PROG), file=sys.stderr)
        return EXIT_USAGE
    try:
        path = find_config_file(args.config)
        data, overrides = read_config_data(path), overrides_from_args(args)
        weak = _take_weak_token(data.get("web"), overrides)
        config = config_from_data(data, overrides, str(path) if path else "configuration")
    except CONFIG_ERRORS as exc:
        print(safe(error_line(exc, PROG), multiline=True), file=sys.stderr)
        return EXIT_USAGE
    print(f"checking {path or 'the default configuration (no uav.toml found)'}", flush=True)
    worst = Level.OK
    for finding in run_checks(config, weak, args.heartbeat_timeout):
        print(safe(finding.line()), flush=True)
        worst = max(worst, finding.level)
    return EXIT_BLOCKED if worst is Level.FAIL else EXIT_FLYABLE


def _take_weak_token(web: Any, overrides: dict[str, Any]) -> str:
    """Remove a web_token the platform would refuse (so the rest loads and is checked); return it, or ""."""
    weak = ""
    for table in (web if isinstance(web, dict) else {}, overrides):
        token = table.get("web_token")
        if isinstance(token, str) and token and token_problem(token):
            weak = table.pop("web_token")
    return weak


def run_checks(config: Config, weak_token: str, heartbeat_timeout_s: float) -> list[Finding]:
    """Every check, in the order a crew would fix things; each bounded."""
    found = check_devices.cameras(config)
    gps_offset_ms = None
    fc = config.fc.strip().lower()
    if fc == "none":
        found.append(fail("fc", "fc = none: no flight controller; set fc to the autopilot's connection, e.g. "
                                "serial:///dev/ttyAMA0:921600"))
    elif fc == "sim":
        found.append(ok("fc", "the built-in simulated vehicle (fc = sim): nothing to check"))
    else:
        try:
            connection = parse_connection(config.fc)
        except ConnectError as exc:
            found.append(fail("fc", str(exc)))
        else:
            serial = check_devices.serial_port(connection) if connection.is_serial else []
            found += serial
            if not serial or serial[0].level is not Level.FAIL:  # a port that does not open has no heartbeat
                report = check_link.link(config, connection, heartbeat_timeout_s)
                found += report.findings
                gps_offset_ms = report.gps_offset_ms
    found.append(check_host.clock(gps_offset_ms))
    found.append(check_host.disk(config))
    found += check_host.models()
    found += check_host.cpu()
    found.append(check_host.token(config, weak_token))
    return found
