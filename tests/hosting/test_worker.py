"""The processor worker: newest frame wins, calls are serialized, exceptions are never fatal.

Each test runs with both hosts of a processor: its own process (the default) and a platform thread.
"""

from __future__ import annotations

import asyncio
import itertools
import os
import signal
import threading
import time
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from processors import load_processor
from sources import open_source
from sources.buffer import FrameBuffer
from sources.synthetic import SyntheticSource
from tests.videos import create_video_file
from uav_tui.events import EventLog
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.hosting import child_link
from uav_tui.hosting.frame_ring import MAX_SLOTS
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.pipe import Inbox
from uav_tui.hosting.process_host import SubprocessHost
from uav_tui.hosting.thread_host import ThreadHost

Worker = ThreadHost | SubprocessHost
BOTH = pytest.mark.parametrize("isolation", ["process", "thread"])
"""Run a test with the processor in its own process and on a platform thread."""

SLOW = '''
import os, threading, time

class Slow:
    def __init__(self, delay=0.03):
        self.tmMgr = None
        self.delay = delay
        self.threads = set()
        self.buttons = []

    def photo_processing(self, frame):
        self.threads.add(threading.get_ident())
        time.sleep(self.delay)

    def customize_processing(self, id):
        self.threads.add(threading.get_ident())
        self.buttons.append(id)
        return os.getpid(), sorted(self.threads), self.buttons
'''

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

async def until(condition: Callable[[], object], what: str, timeout: float = 10) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        await asyncio.sleep(0.005)


@asynccontextmanager
async def running_worker(isolation: str, spec: str, on_result: Callable[[ProcessedFrame], None],
                         kwargs: dict[str, Any] | None = None) -> AsyncIterator[Worker]:
    """A started worker of either kind (its ``run()`` task is the caller's)."""
    if isolation == "thread":
        worker: Worker = ThreadHost(load_processor(spec, kwargs), on_result)
    else:
        worker = await SubprocessHost.start(spec, kwargs or {}, on_result, events=EventLog(), on_fault=print)
    try:
        yield worker
    finally:
        worker.close()


async def collect(worker: Worker, results: list[ProcessedFrame], count: int, timeout: float = 10) -> None:
    task = asyncio.create_task(worker.run())
    deadline = time.monotonic() + timeout
    try:
        while len(results) < count and time.monotonic() < deadline:
            await asyncio.sleep(0.01)
    finally:
        task.cancel()
    assert len(results) >= count, f"only {len(results)} frames processed"


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
    signs = [result.vector[0] for result in results]
    expected = [(-1.0) ** sum(stamp < result.t_start_ns for stamp in stamps) for result in results]
    assert signs == expected
    assert not [(stamp, r.frame.seq) for stamp in stamps for r in results if r.t_start_ns <= stamp <= r.t_end_ns]


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
        worker.attach(buffer)
        task = asyncio.create_task(worker.run())
        try:
            for n in range(1, 7):  # one frame at a time: each is processed before the next arrives
                buffer.put(np.zeros((4, 4, 3), np.uint8))
                await until(lambda n=n: len(results) == n, f"frame {n} processed")
        finally:
            task.cancel()
    failed = [r for r in results if r.error]
    assert len(failed) == 3 and worker.snapshot().errors == 3
    assert "failing.py\", line 10" in failed[0].error and "ValueError: bad frame 1" in failed[0].error
    assert all(r.vector is None for r in failed)
    assert all(r.vector == (0.1, 0.0, 0.5) and r.t_vector_ns >= r.t_end_ns >= r.t_start_ns
               for r in results if not r.error)
    assert worker.consecutive_errors == 0  # the last frame succeeded


def test_frame_buffer_counts_overwrites_and_stamps() -> None:
    buffer = FrameBuffer()
    image = np.zeros((2, 2, 3), np.uint8)
    first = buffer.put(image)
    buffer.put(image)
    third = buffer.put(image)
    assert (buffer.captured, buffer.overwritten) == (3, 2)
    assert buffer.latest() is third and third.seq == 3
    assert third.t_mono_ns >= first.t_mono_ns and abs(third.t_wall_ns - time.time_ns()) < 1e9
    buffer.put(image)
    assert buffer.overwritten == 2  # the third frame was read before the fourth replaced it
    assert buffer.wait_newer(4, timeout=0.01) is None
    assert buffer.wait_newer(3, timeout=0.01).seq == 4


def test_a_frame_marked_read_after_newer_ones_came_is_not_counted_overwritten() -> None:
    buffer = FrameBuffer()
    image = np.zeros((2, 2, 3), np.uint8)
    buffer.put(image)  # taken by another process (peek), which says so only once it is done with it
    buffer.put(image)
    buffer.put(image)
    assert buffer.overwritten == 2  # as far as anyone knows yet
    buffer.mark_read(1)
    assert buffer.overwritten == 1  # only frame 2 was never taken
    assert not buffer.wait_read(timeout=0.01)  # the newest, 3, is still unread
    buffer.mark_read(3)
    assert buffer.overwritten == 1 and buffer.wait_read(timeout=0.01)


DRAWING = '''
class Drawing:
    def __init__(self):
        self.count = 0

    def photo_processing(self, frame):
        self.count += 1
        frame[:8, :8] = self.count % 251  # the overlay: which call drew on this frame
'''


async def test_a_replay_puts_its_next_frame_while_the_child_processes_this_one(tmp_path: Path) -> None:
    """Process isolation, ``realtime=0``: every frame is processed, and frame n+1 is decoded and put as soon as
    the child claimed frame n (before its result is back), so the child finds it waiting when it is done."""
    (tmp_path / "slow.py").write_text(SLOW)
    video = create_video_file(tmp_path / "clip.mp4", frames=10)
    source = open_source(f"file:{video}?realtime=0")
    results: list[ProcessedFrame] = []
    try:
        async with running_worker("process", f"{tmp_path}/slow.py:Slow", results.append, {"delay": 0.05}) as worker:
            worker.attach(source.buffer)
            await collect(worker, results, 8)
    finally:
        source.close()
    assert [r.frame.seq for r in results] == list(range(1, len(results) + 1))  # none skipped
    assert source.get_properties()["frames_dropped"] == 0
    put_while_processing = [nxt.frame.t_mono_ns < cur.t_end_ns for cur, nxt in itertools.pairwise(results[1:])]
    assert all(put_while_processing), put_while_processing


KEEPER = """
class Keeper:
    def __init__(self):
        self.kept = []

    def photo_processing(self, frame):
        self.kept.append(frame)  # a processor that keeps every frame (a history for its own use)

    def customize_processing(self, n):
        self.kept.clear()
"""


async def test_a_replay_resumes_when_the_processor_lets_go_of_every_slot(tmp_path: Path) -> None:
    """Process isolation, ``realtime=0``: a processor that keeps every frame holds every shared-memory slot, and the
    replay waits (nothing overwritten, nothing skipped); the moment it lets go, the frame that found no slot is
    handed over and the replay goes on. That frame used to stay marked as handed over, and the replay stalled."""
    (tmp_path / "keeper.py").write_text(KEEPER)
    source = open_source(f"file:{create_video_file(tmp_path / 'clip.mp4', frames=20)}?realtime=0")
    seqs: list[int] = []

    async def stalled(timeout: float = 10) -> int:
        deadline, count = time.monotonic() + timeout, -1
        while len(seqs) != count and time.monotonic() < deadline:
            count = len(seqs)
            await asyncio.sleep(0.3)
        return count

    try:
        async with running_worker("process", f"{tmp_path}/keeper.py:Keeper",
                                  lambda result: seqs.append(result.frame.seq)) as worker:
            worker.attach(source.buffer)
            task = asyncio.create_task(worker.run())
            held = await stalled()
            assert 0 < held <= MAX_SLOTS  # the processor holds every slot: the replay waits
            await worker.call("customize_processing", 1)  # it lets go
            deadline = time.monotonic() + 10
            while len(seqs) < held + 5 and time.monotonic() < deadline:
                await asyncio.sleep(0.01)
            task.cancel()
    finally:
        source.close()
    assert len(seqs) >= held + 5, f"stalled again at {len(seqs)} frames"
    assert seqs == list(range(1, len(seqs) + 1))  # none skipped


IDLE = """
class Idle:
    def photo_processing(self, frame):
        pass

    def customize_processing(self, n):
        return n
"""


async def test_results_closer_together_than_the_poll_period_are_read_in_batches(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Process isolation: a replay's results, closer together than ``RESULTS_POLL_S``, are read in batches instead
    of each waking the loop, none lost or out of order; once they stop, the pipe is watched again, so a lone reply
    is read as it comes, not a poll later; and a child killed while its results are polled is still reported."""
    poll_s = 0.2
    monkeypatch.setattr(child_link, "RESULTS_POLL_S", poll_s)
    batches: list[int] = []
    read = Inbox.read

    def counted_read(inbox: Inbox) -> list[Any] | None:
        messages = read(inbox)
        if messages:
            batches.append(len(messages))
        return messages

    monkeypatch.setattr(Inbox, "read", counted_read)
    (tmp_path / "idle.py").write_text(IDLE)
    video = create_video_file(tmp_path / "clip.mp4", frames=20)
    seqs: list[int] = []
    faults: list[str] = []
    worker = await SubprocessHost.start(f"{tmp_path}/idle.py:Idle", {}, lambda result: seqs.append(result.frame.seq),
                                       events=EventLog(), on_fault=faults.append)
    task = asyncio.create_task(worker.run())
    try:
        replay = open_source(f"file:{video}?realtime=0")
        try:
            worker.attach(replay.buffer)
            await until(lambda: len(seqs) >= 60, "60 results")
        finally:
            replay.close()
        await asyncio.sleep(3 * poll_s)  # a poll found nothing new: the pipe is watched again
        assert seqs == list(range(1, len(seqs) + 1))
        assert max(batches) >= 5 and len(batches) < len(seqs) / 4, batches

        asked = time.monotonic()
        assert (await worker.call("customize_processing", 7)).value == 7
        assert time.monotonic() - asked < poll_s / 2

        replay = open_source(f"file:{video}?realtime=0")
        try:
            worker.attach(replay.buffer)
            polled = len(seqs)
            await until(lambda: len(seqs) >= polled + 20, "20 more results")
            os.kill(worker.state().pid, signal.SIGKILL)
            await until(lambda: faults, "the death reported")
        finally:
            replay.close()
        assert "SIGKILL" in faults[0], faults
    finally:
        task.cancel()
        worker.close()


@pytest.mark.parametrize("camera", ["file", "synthetic"])
async def test_frames_kept_by_readers_are_never_overwritten(tmp_path: Path, camera: str) -> None:
    """Process isolation: a reader may keep ``result.frame.image`` (a shared-memory slot) as long as it likes.

    A file is decoded straight into the slots; the synthetic camera draws its own arrays, copied in.
    """
    (tmp_path / "drawing.py").write_text(DRAWING)
    video = create_video_file(tmp_path / "clip.mp4", frames=20)
    source = open_source(f"file:{video}?realtime=0" if camera == "file" else "synthetic:?fps=200&width=160&height=120")
    kept: list[tuple[np.ndarray, np.ndarray]] = []
    processed = 0

    def on_result(result: ProcessedFrame) -> None:
        nonlocal processed
        processed += 1
        if processed % 10 == 0 and len(kept) < 5:
            kept.append((result.frame.image, result.frame.image.copy()))  # the view, and what it showed then

    try:
        async with running_worker("process", f"{tmp_path}/drawing.py:Drawing", on_result) as worker:
            worker.attach(source.buffer)
            task = asyncio.create_task(worker.run())
            deadline = time.monotonic() + 20
            while processed < 200 and time.monotonic() < deadline:
                await asyncio.sleep(0.01)
            task.cancel()
    finally:
        source.close()
    assert processed >= 200 and len(kept) == 5
    overlays = [int(copy[0, 0, 0]) for _, copy in kept]
    assert overlays == [n % 251 for n in (10, 20, 30, 40, 50)]  # the child's drawing reached the platform
    for view, copy in kept:
        assert np.array_equal(view, copy)  # 150 frames later, still the same pixels
