"""Both processor hosts: newest frame wins, calls are serialized, exceptions are never fatal.

Each test runs with both hosts of a processor: its own process (the default) and a platform thread.
"""

from __future__ import annotations

import asyncio
import os
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from sources.buffer import FrameBuffer
from sources.synthetic import SyntheticSource
from tests.hosting.hosts import BOTH, SLOW, collect, one_at_a_time, running_worker, until
from uav_tui.events import EventLog
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.process_host import SubprocessHost

GATED = '''
import time
from collections.abc import Callable
from pathlib import Path

class Gated:
    """Each frame waits until the file ``gate`` exists (at most 30 s)."""

    def __init__(self, gate):
        self.tmMgr = None
        self.gate = Path(gate)

    def photo_processing(self, frame):
        deadline = time.monotonic() + 30
        while not self.gate.exists() and time.monotonic() < deadline:
            time.sleep(0.005)
'''

STEERED = '''
class Steered:
    def __init__(self):
        self.tmMgr = None
        self.sign = 1.0

    def customize_processing(self, id):
        self.sign = -self.sign

    def photo_processing(self, frame):
        self.vector = (self.sign, 0.0, 1.0)

    def getPreparedVector(self):
        return self.vector
'''

FAILING = '''
class Failing:
    def __init__(self):
        self.tmMgr = None
        self.calls = 0

    def photo_processing(self, frame):
        self.calls += 1
        if self.calls % 2:
            raise ValueError(f"bad frame {self.calls}")

    def getPreparedVector(self):
        return (0.1, 0.0, 0.5)
'''

@BOTH
async def test_slow_processor_skips_frames_and_counts_them(tmp_path: Path, isolation: str) -> None:
    (tmp_path / "slow.py").write_text(SLOW)
    source = SyntheticSource(fps=200, width=160, height=120)
    results: list[ProcessedFrame] = []
    assert source.open()
    try:
        async with running_worker(isolation, f"{tmp_path}/slow.py:Slow", results.append, {"delay": 0.03}) as worker:
            worker.attach(source.buffer)
            await collect(worker, results, 20)
    finally:
        source.close()
    seqs = [r.frame.seq for r in results]
    assert seqs == sorted(seqs) and len(set(seqs)) == len(seqs)
    stats = worker.snapshot()
    assert stats.frames_skipped == seqs[-1] - seqs[0] + 1 - len(seqs) > 0
    assert stats.processing_ms_p50 >= 30 * 0.9  # sleep(0.03) never takes less


@pytest.mark.parametrize("save_images", [True, False])
async def test_saved_images_are_sent_only_when_the_platform_records(save_images: bool) -> None:
    """With recording off, ``tmMgr.save`` in the child sends its columns, never the image it would drop."""
    telemetry = TelemetryManager(None)
    saved: list[tuple[np.ndarray | None, dict[str, Any]]] = []
    telemetry.saver = lambda image, extra: saved.append((image, extra))
    source = SyntheticSource(fps=100, width=160, height=120)
    results: list[ProcessedFrame] = []
    assert source.open()
    try:
        worker = await SubprocessHost.start("tests.recording.recorder_processors:SaveEveryFrame", {}, results.append,
                                           events=EventLog(), on_fault=print, save_images=save_images,
                                           save_max_hz=0)
        try:
            worker.bind_telemetry(telemetry)
            worker.attach(source.buffer)
            await collect(worker, results, 5)
        finally:
            worker.close()
    finally:
        source.close()
    assert [extra for _, extra in saved[:5]] == [{"n": n} for n in range(1, 6)]
    images = [image for image, _ in saved]
    if save_images:
        assert all(image is not None and image.shape == (120, 160, 3) for image in images)
    else:
        assert images == [None] * len(images)


@BOTH
async def test_a_busy_processor_gets_the_newest_frame_next(tmp_path: Path, isolation: str) -> None:
    (tmp_path / "gated.py").write_text(GATED)
    gate = tmp_path / "gate"
    buffer = FrameBuffer()
    results: list[ProcessedFrame] = []
    async with running_worker(isolation, f"{tmp_path}/gated.py:Gated", results.append, {"gate": str(gate)}) as worker:
        worker.attach(buffer)
        task = asyncio.create_task(worker.run())
        try:
            buffer.put(np.zeros((4, 4, 3), np.uint8))
            await until(lambda: worker.busy_s > 0, "frame 1 being processed")
            for _ in range(4):  # frames 2..5 arrive while frame 1 is being processed
                buffer.put(np.zeros((4, 4, 3), np.uint8))
            gate.touch()
            await until(lambda: len(results) >= 2, "two processed frames")
        finally:
            task.cancel()
    assert [r.frame.seq for r in results] == [1, 5]  # 2, 3 and 4 were replaced, never queued
    assert buffer.overwritten == 3 and worker.snapshot().frames_skipped == 3


@BOTH
async def test_all_calls_run_on_one_thread(tmp_path: Path, isolation: str) -> None:
    (tmp_path / "slow.py").write_text(SLOW)
    buffer = FrameBuffer()
    results: list[ProcessedFrame] = []
    async with running_worker(isolation, f"{tmp_path}/slow.py:Slow", results.append, {"delay": 0.005}) as worker:
        worker.attach(buffer)
        task = asyncio.create_task(worker.run())
        for _ in range(5):
            buffer.put(np.zeros((4, 4, 3), np.uint8))
            pid, threads, buttons = (await worker.call("customize_processing", 2)).value
            await asyncio.sleep(0.01)
        task.cancel()
    assert results and buttons == [2] * 5
    assert len(threads) == 1 and threading.get_ident() not in threads
    assert (pid != os.getpid()) == (isolation == "process")


@BOTH
async def test_a_call_is_stamped_when_the_processor_began_it(tmp_path: Path, isolation: str) -> None:
    """Frames come without a pause; each F-key flips the processor's sign. The frames it started after a call's
    stamp saw that call, and no frame before did: the stamp says before which frame a replay must give it."""
    (tmp_path / "steered.py").write_text(STEERED)
    buffer = FrameBuffer()
    results: list[ProcessedFrame] = []
    stamps: list[int] = []
    feeding = threading.Event()
    feeder = threading.Thread(target=_feed, args=(buffer, feeding), daemon=True)
    async with running_worker(isolation, f"{tmp_path}/steered.py:Steered", results.append) as worker:
        worker.attach(buffer)
        task = asyncio.create_task(worker.run())
        feeder.start()
        try:
            for calls in range(1, 6):
                await until(lambda calls=calls: len(results) >= 20 * calls, f"{20 * calls} results")
                asked = time.monotonic_ns()
                stamps.append((await worker.call("customize_processing", 1)).t_taken_ns)
                assert asked < stamps[-1] < time.monotonic_ns()
            await until(lambda: len(results) >= 120, "120 results")
        finally:
            feeding.set()
            feeder.join()
            task.cancel()
    signs = [result.outcome.vector[0] for result in results]
    expected = [(-1.0) ** sum(stamp < result.outcome.t_start_ns for stamp in stamps) for result in results]
    assert signs == expected
    assert not [(stamp, r.frame.seq) for stamp in stamps for r in results
                if r.outcome.t_start_ns <= stamp <= r.outcome.t_end_ns]


def _feed(buffer: FrameBuffer, stop: threading.Event) -> None:
    """Put a frame every 0.2 ms until ``stop``: the processor always has a newer one waiting."""
    image = np.zeros((4, 4, 3), np.uint8)
    while not stop.wait(0.0002):
        buffer.put(image)


@BOTH
async def test_exceptions_are_caught_counted_and_keep_the_loop_alive(tmp_path: Path, isolation: str) -> None:
    (tmp_path / "failing.py").write_text(FAILING)
    buffer = FrameBuffer()
    results: list[ProcessedFrame] = []
    async with running_worker(isolation, f"{tmp_path}/failing.py:Failing", results.append) as worker:
        await one_at_a_time(worker, buffer, results, 6)
    failed = [r for r in results if r.outcome.error]
    assert len(failed) == 3 and worker.snapshot().errors == 3
    assert "failing.py\", line 10" in failed[0].outcome.error and "ValueError: bad frame 1" in failed[0].outcome.error
    assert all(r.outcome.vector is None for r in failed)
    assert all(o.vector == (0.1, 0.0, 0.5) and o.t_vector_ns >= o.t_end_ns >= o.t_start_ns
               for o in (r.outcome for r in results) if not o.error)
    assert worker.consecutive_errors == 0  # the last frame succeeded
