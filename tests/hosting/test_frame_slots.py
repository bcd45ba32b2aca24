"""The subprocess host's shared-memory slots: a replay puts its next frame while the child works, waits while
the processor holds every slot, and never overwrites a frame a reader still holds."""

from __future__ import annotations

import asyncio
import itertools
import os
import signal
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from sources import open_source
from tests.hosting.hosts import SLOW, collect, running_worker, until
from tests.videos import create_video_file
from uav_tui.events import EventLog
from uav_tui.hosting import child_link
from uav_tui.hosting.frame_ring import MAX_SLOTS
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.pipe import Inbox
from uav_tui.hosting.process_host import SubprocessHost

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
        # 0.3 s a frame: the next frame's decode and put (a few ms) has time to land while the child works, however
        # loaded the machine (at 0.05 s a frame, one of six came late beside other tests)
        async with running_worker("process", f"{tmp_path}/slow.py:Slow", results.append, {"delay": 0.3}) as worker:
            worker.attach(source.buffer)
            await collect(worker, results, 8)
    finally:
        source.close()
    assert [r.frame.seq for r in results] == list(range(1, len(results) + 1))  # none skipped
    assert source.get_properties()["frames_dropped"] == 0
    put_while_processing = [nxt.frame.t_mono_ns < cur.outcome.t_end_ns for cur, nxt in itertools.pairwise(results[1:])]
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
    poll_s = 1.0  # a reply read at once (a round trip of milliseconds quiet) against one read a poll later: at 0.2 s, a
    # loaded machine's round trip (0.16 s at load 20) came near the bound, half a poll
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
