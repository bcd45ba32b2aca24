"""A processor's throughput through the whole platform: one run of a video file, measured (FPS, CPU, latency).

``uav-tui bench`` and ``scripts/bench_pipeline.py`` measure with :func:`platform_run`: the platform as it flies
(``file:VIDEO`` through the capture thread, the frame buffer and the processor's host), without a vehicle or a
recording, after a warm-up; CPU counts the platform's process and the processor's own.
"""

from __future__ import annotations

import asyncio
import os
import time
from dataclasses import dataclass

import numpy as np

from uav_tui.config import load_config
from uav_tui.core import UavCore
from uav_tui.errors import UavError
from uav_tui.relays.contract import HandledFrame
from uav_values.box import PixelBox

WARM_UP_S = 3.5
"""Before measuring: decoder and caches warm, and the file source has chosen its decoder thread count (a window
on each, see ``sources.decoder_threads``)."""


class TooFewFrames(UavError):
    """A run processed fewer than two frames in its measured time: nothing to measure."""


@dataclass(frozen=True)
class Replayed:
    """The frames a platform run processed, by capture sequence number (1: the video's first frame)."""

    selected: int | None
    """The frame the target was selected on (csrt), None without one."""
    first: int
    last: int
    """The measured frames, both included."""
    seqs: list[int]
    """The measured frames it processed: all from ``first`` to ``last`` unless it skipped some (a late reader
    skips frames, as the camera's newest frame wins)."""
    boxes: list[PixelBox | None]
    """What the processor tracked after each frame of ``seqs`` (its ``box``)."""


def latency_percentiles(ms: np.ndarray) -> dict[str, float]:
    return {"latency_ms_p50": float(np.percentile(ms, 50)), "latency_ms_p95": float(np.percentile(ms, 95))}


def cpu_s(pid: int | None) -> float:
    """CPU seconds (user + system) of another process, from /proc; 0 when there is none."""
    if pid is None or pid == os.getpid():
        return 0.0
    with open(f"/proc/{pid}/stat") as stat:
        fields = stat.read().rpartition(")")[2].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


async def platform_run(source: str, processor: str, isolation: str, seconds: float, roi: PixelBox | None, *,
                       warm_up_s: float = WARM_UP_S) -> tuple[dict[str, float], Replayed]:
    """The measures of one run (``fps``, ``cpu_s_per_frame``, ``frames``, hand-off and capture-to-result
    latency p50/p95 in ms), and which frames it processed."""
    core = UavCore(load_config(None, {"source": source, "processor": processor, "fc": "none", "record": False,
                                      "isolation": isolation, "processor_call_timeout": 30.0}))
    results: list[tuple[int, int, int, int]] = []  # (seq, captured, started, ready): never keep the images
    boxes: list[PixelBox | None] = []
    selected: list[int] = []

    def record(r: HandledFrame) -> None:
        done = r.outcome
        results.append((r.frame.seq, r.frame.t_mono_ns, done.t_start_ns, done.t_vector_ns or done.t_end_ns))
        boxes.append(r.outcome.box)
        if r.outcome.box is not None and not selected:
            selected.append(r.frame.seq)  # the first frame tracked: the one the target was selected on

    await core.start()
    try:
        core.add_frame_listener(record)
        if roi is not None:
            await core.execute("roi {} {} {} {}".format(*roi))
        await asyncio.sleep(warm_up_s)
        assert core.worker is not None, "the processor did not start"
        child = core.worker.state().pid
        results.clear()
        boxes.clear()
        wall0, cpu0, child0 = time.perf_counter(), time.process_time(), cpu_s(child)
        await asyncio.sleep(seconds)
        wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0 + cpu_s(child) - child0
        snapshot, measured_boxes = list(results), boxes[:len(results)]
    finally:
        await core.stop()
    if len(snapshot) < 2:
        raise TooFewFrames(f"{processor} processed {len(snapshot)} frames in {seconds:g} s: measure for longer")
    stamps = np.array(snapshot, dtype=np.int64).reshape(-1, 4)
    ready = np.maximum(stamps[1:, 1], stamps[:-1, 3])  # the frame is there and the processor is free
    handoff = np.clip(stamps[1:, 2] - ready, 0, None) / 1e6
    measures = {
        "fps": len(snapshot) / wall,
        "cpu_s_per_frame": cpu / max(1, len(snapshot)),
        "frames": len(snapshot),
        "handoff_ms_p50": float(np.percentile(handoff, 50)),
        "handoff_ms_p95": float(np.percentile(handoff, 95)),
        **latency_percentiles((stamps[:, 3] - stamps[:, 1]) / 1e6),  # capture to result
    }
    seqs = [int(seq) for seq in stamps[:, 0]]
    return measures, Replayed(selected[0] if selected else None, seqs[0], seqs[-1], seqs, measured_boxes)
