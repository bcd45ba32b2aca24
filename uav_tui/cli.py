"""The ``uav-tui`` command: run the platform (TUI or ``--no-ui``) and its tools.

``uav-tui [options]`` runs; ``uav-tui sim`` starts the simulated vehicle on its own;
``uav-tui runs`` lists recorded runs; ``uav-tui report [RUN]`` draws a run's plots; ``uav-tui replay RUN...``
replays recorded runs through a processor; ``uav-tui eval DATA`` scores processors on annotated video;
``uav-tui bench`` measures each reference processor's FPS and CPU on this computer;
``uav-tui calibrate`` writes a camera's calibration file from views of a chessboard; ``uav-tui service`` installs
the platform as a boot service; ``uav-tui doctor`` checks a field setup.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import math
import sys
from pathlib import Path

from uav_tui.arguments import ArgumentParser
from uav_tui.config import add_config_flags, find_config_file, load_config, overrides_from_args
from uav_tui.errors import CONFIG_ERRORS, error_line
from uav_tui.flight.commands import help_text
from uav_tui.output.text import SafeFormatter, safe

TOOLS = ("sim", "runs", "report", "export", "replay", "eval", "bench", "calibrate", "service", "doctor")
"""Sub-commands; anything else on the command line configures a run."""


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(
        prog="uav-tui", suggest=TOOLS,
        description="Camera -> your algorithm -> flight controller, with an operator dashboard.",
        epilog=f"tools: uav-tui sim | runs | report [RUN] | export [RUN] | replay RUN... | eval DATA | bench | "
               f"calibrate | service install|remove|status | doctor (each has --help)\n\n"
               f"commands (keys, --script, web):\n{help_text()}",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--config", metavar="PATH", help="TOML file (default: $UAV_TUI_CONFIG, ./uav.toml, "
                        "~/.config/uav-tui/uav.toml)")
    parser.add_argument("--no-ui", action="store_true", help="run headless: a status line every second")
    parser.add_argument("--json", action="store_true", help="with --no-ui: print JSON lines instead")
    parser.add_argument("--duration", type=seconds, metavar="S", help="stop by itself after S seconds")
    parser.add_argument("--script", metavar="FILE", help="run operator commands from FILE, one per line")
    parser.add_argument("--on-hangup", choices=("stop", "continue"), default="stop",
                        help="when the terminal is lost (SIGHUP): hold and exit (default), or keep running headless")
    parser.add_argument("--log-level", default="WARNING", choices=("DEBUG", "INFO", "WARNING", "ERROR"))
    add_config_flags(parser)
    return parser


def seconds(text: str) -> float:
    """A positive, finite number of seconds (``--duration``): anything else is refused before the run starts."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"{text} must be a positive number of seconds (the run stops by itself "
                                         "after that long; leave --duration out to run until stopped)")
    return value


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] in TOOLS:
        return _run_tool(argv[0], argv[1:])
    args = build_parser().parse_args(argv)
    setup_logging(args.log_level)
    try:
        config = load_config(find_config_file(args.config), overrides_from_args(args))
        script = None
        if args.script:
            from uav_tui.headless import load_script

            script = load_script(Path(args.script), config.safety)
    except CONFIG_ERRORS as exc:
        print(safe(error_line(exc), multiline=True), file=sys.stderr)
        return 2
    if args.no_ui:
        from uav_tui.headless import HeadlessRunner

        runner = HeadlessRunner(config, duration=args.duration, script=script, json_lines=args.json,
                                on_hangup=args.on_hangup)
        try:
            return asyncio.run(runner.run())
        except KeyboardInterrupt:
            return 130
    from uav_tui.tui import run_tui

    return run_tui(config, duration=args.duration, script=script, on_hangup=args.on_hangup)


def setup_logging(level: str) -> None:
    """Log records to stderr through :class:`SafeFormatter` (escaped, passwords hidden)."""
    handler = logging.StreamHandler()
    handler.setFormatter(SafeFormatter("%(asctime)s %(levelname)s %(name)s: %(message)s"))
    logging.basicConfig(level=level, handlers=[handler])


def _run_tool(name: str, argv: list[str]) -> int:
    if name == "sim":
        from controllers.sim.__main__ import main as sim_main

        return sim_main(argv, parser_class=ArgumentParser)
    if name == "replay":
        from uav_tui.replay.cli import main as replay_main

        return replay_main(argv)
    if name == "eval":
        from uav_tui.evaluation import cli as eval_cli

        return eval_cli.main(argv)
    if name == "bench":
        from uav_tui.evaluation import bench_cli

        return bench_cli.main(argv)
    if name == "calibrate":
        from uav_tui import calibrate_cli

        return calibrate_cli.main(argv)
    if name == "service":
        from uav_tui.field import service

        return service.main(argv)
    if name == "doctor":
        from uav_tui.field import doctor

        return doctor.main(argv)
    from uav_tui.recorded import runs_cli

    return runs_cli.main(name, argv)
