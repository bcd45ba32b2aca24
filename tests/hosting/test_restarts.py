"""Restarts of a processor's process: given up after five in a minute, and a replay goes on with the restarted
processor from the frame after the one the dead one had."""

from __future__ import annotations

import asyncio
import os
import resource
from pathlib import Path

import numpy as np

from sources import open_source
from sources.buffer import FrameBuffer
from tests.core.flight_helpers import wait_until
from tests.videos import create_video_file
from uav_tui.events import EventLog
from uav_tui.hosting.host import HostPhase, HostState, ProcessedFrame
from uav_tui.hosting.process_host import SubprocessHost

CRASH_LOOP = '''
import os
from pathlib import Path

class CrashLoop:
    """Dies on its first frame; every later construction fails."""

    def __init__(self, marker):
        if Path(marker).exists():
            raise RuntimeError("still broken")
        self.marker = marker

    def photo_processing(self, frame):
        Path(self.marker).touch()
        os._exit(3)
'''


def test_the_host_state_reads_as_its_text_always_did() -> None:
    phases = [HostPhase(HostState.STARTING), HostPhase(HostState.RUNNING), HostPhase(HostState.RESTARTING, 2),
              HostPhase(HostState.CRASHED), HostPhase(HostState.CRASHED, reason="exited with code 3")]
    assert [str(p) for p in phases] == ["starting", "running", "restarting 2", "crashed", "crashed: exited with code 3"]


async def test_after_five_restarts_in_a_minute_it_gives_up_and_says_so(tmp_path: Path) -> None:
    (tmp_path / "crash_loop.py").write_text(CRASH_LOOP)
    events, faults = EventLog(), []
    worker = await SubprocessHost.start(f"{tmp_path}/crash_loop.py:CrashLoop", {"marker": str(tmp_path / "died")},
                                       print, events=events, on_fault=faults.append, first_backoff_s=0.05)
    buffer = FrameBuffer()
    worker.attach(buffer)
    task = asyncio.create_task(worker.run())
    try:
        buffer.put(np.zeros((4, 4, 3), np.uint8))
        await wait_until(lambda: worker.state().phase.reason, 30, "the platform to give up")
    finally:
        task.cancel()
        await asyncio.gather(task, return_exceptions=True)
    messages = [e.message for e in events.recent]
    restarts = [m.split(":")[0] for m in messages if m.startswith("restart ")]
    assert restarts == [f"restart {n} failed" for n in range(1, 6)]
    assert any(m.startswith("gave up: 5 restarts within 60 s") for m in messages)
    phase = worker.state().phase
    assert phase == HostPhase(HostState.CRASHED, reason="restart failed: " + messages[-2].partition(" failed: ")[2])
    assert str(phase) == f"crashed: {phase.reason}"
    assert len(faults) == 1 and "exited with code 3" in faults[0]  # autonomy was stopped once, at the death


DIES_ONCE = '''
import os
from pathlib import Path

class DiesOnce:
    """Sees one parked car; dies on its third frame, the first time it runs."""

    def __init__(self, marker):
        self.marker, self.frames, self.detections = Path(marker), 0, []

    def photo_processing(self, frame):
        self.frames += 1
        if self.frames == 3 and not self.marker.exists():
            self.marker.touch()
            os._exit(3)
        self.detections = [((10, 10, 20, 20), "car", 0.9)]
'''


async def test_a_replay_goes_on_with_the_restarted_processor_after_the_frame_the_dead_one_had(tmp_path: Path) -> None:
    """``realtime=0`` waits for each frame's claim; a child that dies on frame 3 (it had claimed it) is replaced
    and the replay resumes with the restarted one at frame 4: only the frame it died on is lost. The restarted
    one's tracks do not take the numbers recorded before (issue 50): its car is a new track."""
    (tmp_path / "dies_once.py").write_text(DIES_ONCE)
    video = create_video_file(tmp_path / "clip.mp4", width=64, height=48)
    source = open_source(f"file:{video}?realtime=0")
    results: list[ProcessedFrame] = []
    worker = await SubprocessHost.start(f"{tmp_path}/dies_once.py:DiesOnce", {"marker": str(tmp_path / "died")},
                                       results.append, events=EventLog(), on_fault=print, first_backoff_s=0.05)
    worker.attach(source.buffer)
    task = asyncio.create_task(worker.run())
    try:
        await wait_until(lambda: len(results) >= 10, 30, "ten frames from the restarted processor")
    finally:
        task.cancel()
        await asyncio.gather(task, return_exceptions=True)
        source.close()
    seqs = [r.frame.seq for r in results]
    assert seqs == [1, 2, *range(4, len(seqs) + 2)]
    ids = [r.outcome.detections[0].track_id for r in results if r.outcome.detections]
    assert ids == [0, 0, *[1] * (len(seqs) - 2)], ids


async def test_a_restart_the_system_refuses_for_lack_of_descriptors_is_tried_again(tmp_path: Path) -> None:
    """Issue 47, 4: with no descriptor left when the processor died, the restart failed with an OSError that ended
    the restart task silently ("restarting 1" for good). Now it is said once, not counted, and tried again."""
    (tmp_path / "dies_once.py").write_text(DIES_ONCE)
    events = EventLog()
    limit = resource.getrlimit(resource.RLIMIT_NOFILE)

    filler: list[int] = []

    def free_again() -> None:
        for fd in filler:
            os.close(fd)
        filler.clear()
        resource.setrlimit(resource.RLIMIT_NOFILE, limit)

    def no_descriptors_left(reason: str) -> None:  # at the death: every new descriptor fails (EMFILE) for 1 s
        resource.setrlimit(resource.RLIMIT_NOFILE, (max(int(fd) for fd in os.listdir("/proc/self/fd")), limit[1]))
        while True:  # the free numbers below the limit (closed earlier) taken too
            try:
                filler.append(os.open(os.devnull, os.O_RDONLY))
            except OSError:
                break
        asyncio.get_running_loop().call_later(1.0, free_again)

    worker = await SubprocessHost.start(f"{tmp_path}/dies_once.py:DiesOnce", {"marker": str(tmp_path / "died")},
                                       lambda result: None, events=events, on_fault=no_descriptors_left,
                                       first_backoff_s=0.05)
    buffer = FrameBuffer()
    worker.attach(buffer)
    task = asyncio.create_task(worker.run())
    try:
        for _ in range(3):
            buffer.put(np.zeros((4, 4, 3), np.uint8))
            await asyncio.sleep(0.1)
        await wait_until(lambda: worker.state().phase.state is HostState.RUNNING and (tmp_path / "died").exists(), 30,
                         "the processor to be restarted once descriptors are free again")
    finally:
        task.cancel()
        await asyncio.gather(task, return_exceptions=True)
        free_again()
    messages = [e.message for e in events.recent]
    refused = [m for m in messages if "could not start a process" in m]
    assert len(refused) == 1 and "Too many open files" in refused[0], messages
    assert any(m.startswith("processor restarted (pid") for m in messages)
