"""``uav-tui replay RUN... --processor X``: replay recorded runs through a processor, each into a new run."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from controllers.replay_timeline import parse_speed
from uav_tui.arguments import ArgumentParser
from uav_tui.config import find_config_file, load_config, overrides_from_args
from uav_tui.errors import KNOWN_ERRORS
from uav_tui.evaluation.jobs import run_jobs
from uav_tui.output.text import safe
from uav_tui.recorded.runs_cli import find_run
from uav_tui.replay.runner import ReplayJob, processor_text, replay_config, replay_run, summary_line


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(
        prog="uav-tui replay",
        description="Replay recorded runs (their video and telemetry, at the recorded times) through a processor. "
                    "Each replay is written as a new run whose run.json names the source run; vectors are judged "
                    "by the autonomy gate as in the recorded run (autonomy on when it was on) and never sent. "
                    "Exit status: 0, 1 when a replay recorded errors (the processor raised ...), 2 when none ran.")
    parser.add_argument("runs", nargs="+", metavar="RUN", help="run folder, or its name under the runs folder")
    parser.add_argument("--processor", help="processor: short name, module:Class or path/file.py:Class "
                        "(default: each run's own, with its constructor arguments, from its run.json)")
    parser.add_argument("--processor-arg", dest="processor_args", action="append", default=None,
                        metavar="KEY=VALUE", help="constructor argument of --processor (TOML value), repeatable")
    parser.add_argument("--speed", default="1", help="1 = real time (default), 4 = four times as fast, max = every "
                        "frame as fast as the processor goes, deterministic")
    parser.add_argument("--workers", type=int, metavar="N", help="replay N runs at once in local processes "
                        "(default: one per core)")
    parser.add_argument("--cluster", metavar="ADDRESS", help="run the replays on this Dask scheduler "
                        "(tcp://HOST:8786)")
    parser.add_argument("--runs-dir", metavar="DIR", help="where the runs are and the replays go "
                        "(default: runs_dir of the configuration)")
    parser.add_argument("--config", metavar="PATH", help="TOML file (safety limits, runs_dir, processor)")
    return parser


def main(argv: list[str]) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        parse_speed(args.speed)
    except ValueError as exc:
        parser.error(f"--speed: {exc}")
    if args.processor_args and not args.processor:
        parser.error("--processor-arg needs --processor (without it, each run is replayed with its own processor "
                     "and arguments)")
    try:
        config = load_config(find_config_file(args.config), overrides_from_args(args))
        runs_dir = Path(config.recording.runs_dir).expanduser()
        jobs = [ReplayJob(str(find_run(runs_dir, name)), config, args.speed, own_processor=not args.processor)
                for name in args.runs]
        for job in jobs:
            print(safe(f"replaying {Path(job.run).name} through {processor_text(replay_config(job))}"
                       f"{' (its own processor)' if job.own_processor else ''}"), file=sys.stderr)
        results = run_jobs(replay_run, jobs, workers=args.workers, cluster=args.cluster,
                           progress=lambda done, total: print(f"replayed {done}/{total}", file=sys.stderr))
    except KNOWN_ERRORS as exc:
        print(safe(f"uav-tui replay: {exc}", multiline=True), file=sys.stderr)
        return 2
    for result in results:
        print(safe(summary_line(result)))  # run folders and paths: escaped
    failed = sum(1 for result in results if result.errors)
    if failed:
        print(f"uav-tui replay: {failed} of {len(results)} replays had errors (exit status 1)", file=sys.stderr)
    return 1 if failed else 0
