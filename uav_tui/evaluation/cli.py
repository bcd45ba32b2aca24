"""``uav-tui eval``: score processors on annotated sequences (one-pass evaluation); table, JSON, plots."""

from __future__ import annotations

import argparse
import datetime
import shlex
import sys
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from processors.detection import DATA_DIR_ENV
from uav_tui.arguments import ArgumentParser
from uav_tui.config import parse_processor_args
from uav_tui.errors import KNOWN_ERRORS, ConfigError
from uav_tui.evaluation import JobResult, TrackerSpec, evaluate, find_sequences, journal
from uav_tui.evaluation.report import failures, outside_cell, summary, table, write_json, write_plots
from uav_tui.evaluation.sequences import aerial_tracking_set
from uav_tui.output.text import safe

EXAMPLE = """examples:
  uav-tui eval --processor csrt --processor cv:csrt   # the aerial-tracking set ($UAV_TUI_DATA_DIR)
  uav-tui eval data/ --processor csrt --processor-arg mode=paper --processor ~/algos/mine.py:MyTracker
  uav-tui eval data/ --processor cv:kcf --cluster tcp://10.0.0.5:8786
  uav-tui eval data/ --processor csrt --out eval-results/csrt      # interrupted (Ctrl-C, a crash)? go on:
  uav-tui eval data/ --processor csrt --resume eval-results/csrt
  uav-tui eval --mot                    # multi-object tracking of yolo's detections (uav-tui eval --mot --help)

Each job's result is written as it finishes (jobs.jsonl, eval.json), so an interrupted evaluation keeps what is
done and --resume runs only the rest. A processor that raises fails its job alone (the table says where and
why); the exit status is then 1. tmMgr.save writes into DIR/saves/ (at most 100 images a job).

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

    parser = ArgumentParser(
        prog="uav-tui eval", formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Score processors on annotated video: catch_cmd(the first frame's gt box), then photo_processing "
                    "on every frame; the processor's box is compared with the gt (success AUC, precision@20px, "
                    "normalised precision, frames lost while visible, absent frames reported lost, ms/frame).",
        epilog=EXAMPLE.format(trackers=" ".join(f"cv:{name}" for name in sorted(available_trackers()))))
    parser.add_argument("data", nargs="*", type=Path, help="a sequence folder (video.mp4 + gt.txt, or img/ + "
                        "groundtruth_rect.txt, or images with <folder>.txt beside it), or a folder of them (default: "
                        f"the aerial-tracking set in ${DATA_DIR_ENV}, else in shared/data beside the repository)")
    parser.add_argument("--processor", "-p", dest="processors", action=_Processor, metavar="SPEC", required=True,
                        help="what to score, as for a run (csrt, module:Class, file.py:Class) or cv:NAME; repeat")
    parser.add_argument("--processor-arg", action=_ProcessorArg, metavar="KEY=VALUE",
                        help="constructor argument of the preceding --processor (a TOML literal); repeat")
    parser.add_argument("--workers", type=int, metavar="N", help="local worker processes (default: one per core)")
    parser.add_argument("--cluster", metavar="ADDRESS", help="run the jobs on this Dask scheduler "
                        "(tcp://HOST:8786; needs the cluster extra)")
    parser.add_argument("--out", type=Path, metavar="DIR", help="where eval.json and the plots go "
                        "(default: eval-results/<UTC time>)")
    parser.add_argument("--resume", type=Path, metavar="DIR", help="go on with the evaluation in DIR (an earlier "
                        "--out): the jobs already there are not run again")
    parser.add_argument("--threads", type=int, default=1, metavar="N", help="OpenCV and ONNX Runtime threads of "
                        "each job (default 1, so that ms/frame compares across trackers)")
    return parser


def main(argv: list[str]) -> int:
    if "--mot" in argv:
        from uav_tui.evaluation import mot_cli

        return mot_cli.main([arg for arg in argv if arg != "--mot"])
    args = build_parser().parse_args(argv)
    console = Console(highlight=False, width=None if sys.stdout.isatty() else 160)
    results: list[JobResult] = []
    out = args.resume or args.out or Path("eval-results") / datetime.datetime.now(datetime.UTC).strftime(
        "%Y-%m-%dT%H-%M-%SZ")
    try:
        trackers = [TrackerSpec(spec, parse_processor_args(items)) for spec, items in args.processors]
        _check_numbers(args)
        for tracker in trackers:
            tracker.load()  # a wrong name or argument fails here, before any job starts
        args.data = args.data or [aerial_tracking_set()]
        sequences = find_sequences(args.data)
        done = journal.read(out, sequences, args.threads) if args.resume else []
        if not args.resume and (out / journal.JOURNAL).exists():
            raise ConfigError(f"{out} already holds an evaluation ({journal.JOURNAL}): go on with it with --resume "
                              f"{out}, or give another --out", key="out")
        out.mkdir(parents=True, exist_ok=True)
        total, sources = len(sequences) * len(trackers), [str(p) for p in args.data]
        wanted = {(s.name, t.label) for s in sequences for t in trackers}
        results.extend(r for r in done if r.key in wanted)
        if results:
            console.print(f"resuming: {len(results)} of {total} jobs already done in {outside_cell(out)}")

        def finished(result: JobResult) -> None:
            journal.append(out, result)
            results.append(result)
            write_json(summary(results, sources, total_jobs=total), out / "eval.json")
            if not console.is_terminal:  # no bar there: a line per job, so a log or a pipe shows progress
                print(safe(progress_line(result, len(results), total)), flush=True)

        with Progress(TextColumn("eval"), BarColumn(), MofNCompleteColumn(), TextColumn("jobs"),
                      TimeElapsedColumn(), console=console, transient=True) as progress:
            task = progress.add_task("eval", total=total)
            results = evaluate(sequences, trackers, workers=args.workers, cluster=args.cluster, threads=args.threads,
                               saves_dir=out / "saves", done=results, on_result=finished,
                               progress=lambda count, _: progress.update(task, completed=count))
    except KNOWN_ERRORS as exc:
        print(f"uav-tui eval: {safe(str(exc))}", file=sys.stderr)
        return 2
    except (KeyboardInterrupt, BrokenProcessPool) as exc:
        why = "interrupted" if isinstance(exc, KeyboardInterrupt) else f"a worker process died ({exc})"
        print(safe(f"uav-tui eval: {why}; the {len(results)} finished jobs are in {out / 'eval.json'}; go on with: "
                   f"{_resume_command(argv, out)}"), file=sys.stderr)
        return 130 if isinstance(exc, KeyboardInterrupt) else 1
    console.print(table(results))
    for line in failures(results):
        console.print(f"[red]{escape(line)}[/red]")  # failures() made it safe
    written = [write_json(summary(results, sources, total_jobs=total), out / "eval.json"), *write_plots(results, out)]
    for path in written:
        console.print(f"wrote {outside_cell(path)}")
    failed = sum(r.failed for r in results)
    if failed:
        console.print(f"[red]{failed} of {total} jobs failed[/red] (eval.json has their tracebacks)")
    return 1 if failed else 0


def progress_line(result: JobResult, done: int, total: int) -> str:
    """``eval: 3/12 csrt on car1: AUC 0.612, 8.1 ms/frame`` (or why it failed): one finished job, in plain text."""
    if result.scores is None:
        outcome = f"failed at {result.failed_at}: {result.error}"
    else:
        outcome = f"AUC {result.scores.success_auc:.3f}, {result.scores.ms_mean:.1f} ms/frame"
    return f"eval: {done}/{total} {result.tracker} on {result.sequence}: {outcome}"


def _check_numbers(args: argparse.Namespace) -> None:
    if args.workers is not None and args.workers < 1:
        raise ConfigError("--workers must be at least 1", key="workers")
    if args.threads < 1:
        raise ConfigError("--threads must be at least 1", key="threads")
    if args.resume and args.out and args.out.resolve() != args.resume.resolve():
        raise ConfigError(f"--resume {args.resume} writes into that folder: leave out --out {args.out}", key="out")


def _resume_command(argv: list[str], out: Path) -> str:
    """The command line that goes on with this evaluation."""
    given = list(argv)
    if "--resume" not in given:
        given += ["--resume", str(out)]
    return "uav-tui eval " + " ".join(shlex.quote(a) for a in given)
