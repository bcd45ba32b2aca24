"""``uav-tui eval``: score processors on annotated sequences (one-pass evaluation); table, JSON, plots."""

from __future__ import annotations

import argparse
import datetime
import sys
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from uav_tui.config import parse_processor_args
from uav_tui.errors import KNOWN_ERRORS, ConfigError
from uav_tui.evaluation import TrackerSpec, evaluate, find_sequences
from uav_tui.evaluation.report import summary, table, write_json, write_plots

EXAMPLE = """examples:
  uav-tui eval ../shared/data/aerial-tracking --processor csrt --processor cv:csrt
  uav-tui eval data/ --processor csrt --processor-arg mode=paper --processor ~/algos/mine.py:MyTracker
  uav-tui eval data/ --processor cv:kcf --cluster tcp://10.0.0.5:8786

--processor-arg applies to the --processor before it. cv:NAME is a plain OpenCV tracker; this OpenCV has:
  {trackers}"""


class _ProcessorArg(argparse.Action):
    """``--processor-arg KEY=VALUE``: added to the arguments of the last ``--processor``."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, value: Any,
                 option_string: str | None = None) -> None:
        if not namespace.processors:
            parser.error("--processor-arg must follow the --processor it belongs to")
        namespace.processors[-1][1].append(value)


class _Processor(argparse.Action):
    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, value: Any,
                 option_string: str | None = None) -> None:
        namespace.processors = [*(namespace.processors or []), (value, [])]


def build_parser() -> argparse.ArgumentParser:
    from processors.opencv_tracker import available_trackers

    parser = argparse.ArgumentParser(
        prog="uav-tui eval", formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Score processors on annotated video: catch_cmd(frame 0's gt box), then photo_processing on "
                    "every frame; the processor's box is compared with the gt (success AUC, precision@20px, "
                    "normalised precision, frames lost, ms/frame).",
        epilog=EXAMPLE.format(trackers=" ".join(f"cv:{name}" for name in sorted(available_trackers()))))
    parser.add_argument("data", nargs="+", type=Path, help="a sequence folder (video.mp4 + gt.txt, or img/ + "
                        "groundtruth_rect.txt, or images with <folder>.txt beside it), or a folder of them")
    parser.add_argument("--processor", "-p", dest="processors", action=_Processor, metavar="SPEC", required=True,
                        help="what to score, as for a run (csrt, module:Class, file.py:Class) or cv:NAME; repeat")
    parser.add_argument("--processor-arg", action=_ProcessorArg, metavar="KEY=VALUE",
                        help="constructor argument of the preceding --processor (a TOML literal); repeat")
    parser.add_argument("--workers", type=int, metavar="N", help="local worker processes (default: one per core)")
    parser.add_argument("--cluster", metavar="ADDRESS", help="run the jobs on this Dask scheduler "
                        "(tcp://HOST:8786; needs the cluster extra)")
    parser.add_argument("--out", type=Path, metavar="DIR", help="where eval.json and the plots go "
                        "(default: eval-results/<UTC time>)")
    return parser


def main(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    console = Console(highlight=False, width=None if sys.stdout.isatty() else 160)
    try:
        trackers = [TrackerSpec(spec, parse_processor_args(items)) for spec, items in args.processors]
        if args.workers is not None and args.workers < 1:
            raise ConfigError("--workers must be at least 1", key="workers")
        for tracker in trackers:
            tracker.load()  # a wrong name or argument fails here, before any job starts
        sequences = find_sequences(args.data)
        out = args.out or Path("eval-results") / datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H-%M-%SZ")
        out.mkdir(parents=True, exist_ok=True)
        with Progress(TextColumn("eval"), BarColumn(), MofNCompleteColumn(), TextColumn("jobs"),
                      TimeElapsedColumn(), console=console, transient=True) as progress:
            task = progress.add_task("eval", total=len(sequences) * len(trackers))
            results = evaluate(sequences, trackers, workers=args.workers, cluster=args.cluster,
                               progress=lambda done, total: progress.update(task, completed=done))
    except KNOWN_ERRORS as exc:
        print(f"uav-tui eval: {exc}", file=sys.stderr)
        return 2
    console.print(table(results))
    written = [write_json(summary(results, [str(p) for p in args.data]), out / "eval.json"),
               *write_plots(results, out)]
    for path in written:
        console.print(f"wrote {path}")
    return 0
