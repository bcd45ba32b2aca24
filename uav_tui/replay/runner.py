"""Replay one recorded run through a processor: ``run:`` camera + ``replay:`` vehicle, written as a new run."""

from __future__ import annotations

import asyncio
from dataclasses import dataclass, field
from pathlib import Path

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


def replay_run(job: ReplayJob) -> ReplayResult:
    """Replay ``job.run`` (blocks; a module-level function so :func:`uav_tui.jobs.run_jobs` can ship it)."""
    return asyncio.run(replay(job))


def replay_config(job: ReplayJob) -> Config:
    """The configuration of a replay: the run's camera and vehicle, recorded as a new run without video."""
    run_dir = Path(job.run).expanduser()
    if not (run_dir / "run.json").is_file():
        raise UavError(f"{run_dir} is not a recorded run (no run.json); `uav-tui runs` lists them")
    return with_overrides(job.config, source=f"run:{run_dir}", fc=f"replay:{run_dir}?speed={job.speed}",
                          record=True, record_video=False)


async def replay(job: ReplayJob) -> ReplayResult:
    """Run a core on the recorded run until its camera has shown every frame and they were processed."""
    config = replay_config(job)
    core = UavCore(config)
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
                        seconds=loop.time() - started)


async def _until_finished(core: UavCore) -> None:
    source, worker, controller = core.source, core.worker, core.controller
    assert source is not None and worker is not None and controller is not None
    finished = source.finished  # type: ignore[attr-defined]
    while True:
        await asyncio.sleep(POLL_S)
        if core.quit_requested.is_set():
            raise UavError(f"replay of {controller.run_dir} stopped: "  # type: ignore[attr-defined]
                           f"{core.processor_error or 'a task failed'}")
        last = worker.last
        if finished.is_set() and worker.busy_s == 0 and last is not None and last.frame.seq >= source.buffer.newest_seq:
            break
    if core.replay is not None and core.replay.lockstep:  # the telemetry after the last frame, for its interpolation
        while controller.applied < len(controller.samples):  # type: ignore[attr-defined]
            await asyncio.sleep(POLL_S)


def summary_line(result: ReplayResult) -> str:
    """One line per replayed run for the terminal."""
    note = " (no video in that run: its saved frames only)" if result.content != "video" else ""
    return (f"{Path(result.run).name}: {result.frames} frames in {result.seconds:.1f} s "
            f"({result.frames / result.seconds if result.seconds else 0:.0f}/s){note} -> {result.replay}")
