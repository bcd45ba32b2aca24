"""Replay one recorded run through a processor: ``run:`` camera + ``replay:`` vehicle, written as a new run."""

from __future__ import annotations

import asyncio
import json
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from controllers.replay import ReplayController
from sources.run import RunSource
from uav_tui.config import Config, with_overrides
from uav_tui.core import UavCore
from uav_tui.errors import UavError

POLL_S = 0.05
"""How often the runner looks whether the recorded camera has finished."""


@dataclass(frozen=True)
class ReplayJob:
    """One run to replay (picklable: jobs go to worker processes or a Dask cluster)."""

    run: str
    """The recorded run folder."""
    config: Config = field(default_factory=Config)
    """Processor, its arguments, runs_dir, safety limits ... (source and fc are set by the replay)."""
    speed: str = "1"
    """A positive factor of real time, or ``max`` (lockstep: every frame, deterministic)."""
    own_processor: bool = False
    """Replay through the processor and constructor arguments the run's ``run.json`` names, not ``config``'s
    (``uav-tui replay`` without ``--processor``)."""


@dataclass(frozen=True)
class ReplayResult:
    run: str
    replay: str
    """The new run folder."""
    content: str
    """What was replayed: ``video``, or ``saved frames`` for a run recorded before video existed."""
    frames: int
    """Frames processed."""
    seconds: float
    """Time the replay took."""
    processor: str = ""
    """What the frames were processed by: the spec and its constructor arguments."""
    warnings: int = 0
    """Warnings in the replay's events.csv."""
    errors: int = 0
    """Errors in the replay's events.csv (the processor raising on a frame, a call that failed ...)."""


def replay_run(job: ReplayJob) -> ReplayResult:
    """Replay ``job.run`` (blocks; a module-level function so :func:`uav_tui.evaluation.jobs.run_jobs` can ship it)."""
    return asyncio.run(replay(job))


def replay_config(job: ReplayJob) -> Config:
    """The configuration of a replay: the run's camera and vehicle, recorded as a new run without video."""
    run_dir = Path(job.run).expanduser()
    if not (run_dir / "run.json").is_file():
        raise UavError(f"{run_dir} is not a recorded run (no run.json); `uav-tui runs` lists them")
    config = job.config
    if job.own_processor:
        spec, kwargs = recorded_processor(run_dir)
        config = with_overrides(config, processor=spec, processor_args=kwargs)
    return with_overrides(config, source=f"run:{run_dir}", fc=f"replay:{run_dir}?speed={job.speed}",
                          record=True, record_video=False)


def recorded_processor(run_dir: Path) -> tuple[str, dict[str, Any]]:
    """The processor a run was flown with, as ``(spec, constructor arguments)`` (a file by its full path)."""
    try:
        processor = json.loads((run_dir / "run.json").read_text()).get("processor")
    except (OSError, ValueError, AttributeError):
        processor = None
    if not isinstance(processor, dict) or not processor.get("spec"):
        raise UavError(f"{run_dir}/run.json does not say which processor the run had: give --processor")
    spec, path, name = str(processor["spec"]), processor.get("path"), str(processor.get("name", ""))
    if ".py" in spec and path and Path(path).is_file():  # a file named relative to where the flight started
        spec = f"{path}:{name.rpartition(':')[2]}"
    kwargs = processor.get("kwargs")
    return spec, kwargs if isinstance(kwargs, dict) else {}


def processor_text(config: Config) -> str:
    """``spec`` or ``spec (key=value, ...)``: what a replay processes with."""
    kwargs = ", ".join(f"{key}={value!r}" for key, value in config.processor_args.items())
    return f"{config.processor} ({kwargs})" if kwargs else config.processor


async def replay(job: ReplayJob) -> ReplayResult:
    """Run a core on the recorded run until its camera has shown every frame and they were processed."""
    config = replay_config(job)
    core = UavCore(config)
    levels: Counter[str] = Counter()
    core.events.add_listener(lambda event: levels.update((event.level,)))
    loop = asyncio.get_running_loop()
    started = loop.time()
    await core.start()
    try:
        await _until_finished(core)
    finally:
        await core.stop("replay finished")
    assert core.recorder is not None and core.source is not None
    return ReplayResult(run=str(Path(job.run).expanduser()), replay=str(core.recorder.run_dir),
                        content=core.source.get_properties()["content"], frames=core.recorder.frames,
                        seconds=loop.time() - started, processor=processor_text(config),
                        warnings=levels["warning"], errors=levels["error"])


async def _until_finished(core: UavCore) -> None:
    source, worker, controller = core.source, core.worker, core.controller
    assert isinstance(source, RunSource) and worker is not None and isinstance(controller, ReplayController)
    finished = source.finished
    while True:
        await asyncio.sleep(POLL_S)
        if core.quit_requested.is_set():
            raise UavError(f"replay of {controller.run_dir} stopped: "
                           f"{core.processor_error or 'a task failed'}")
        last = worker.last
        if finished.is_set() and worker.busy_s == 0 and last is not None and last.frame.seq >= source.buffer.newest_seq:
            break
    if core.replay is not None and core.replay.lockstep:  # the telemetry after the last frame, for its interpolation
        while controller.applied < len(controller.samples):
            await asyncio.sleep(POLL_S)


def summary_line(result: ReplayResult) -> str:
    """One line per replayed run for the terminal."""
    note = " (no video in that run: its saved frames only)" if result.content != "video" else ""
    problems = ""
    if result.errors or result.warnings:
        problems = (f"; {result.errors} error{'s' * (result.errors != 1)}, {result.warnings} "
                    f"warning{'s' * (result.warnings != 1)} (uav-tui report lists them)")
    return (f"{Path(result.run).name}: {result.frames} frames through {result.processor} in {result.seconds:.1f} s "
            f"({result.frames / result.seconds if result.seconds else 0:.0f}/s){note}{problems} -> {result.replay}")
