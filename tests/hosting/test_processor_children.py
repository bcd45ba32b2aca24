"""The processes a processor starts (a helper with ``subprocess``, workers with ``multiprocessing``) end with it.

They are in its process group: killed with it when it hangs, when it dies, when it is reloaded and when the
platform stops, so a restart loop cannot pile up helpers that eat the memory and the CPU the flight link needs.
Real processes throughout; a process counts as ended once it is gone or a zombie (a container's first process
may never reap the orphans it inherits).
"""

from __future__ import annotations

import asyncio
import os
import signal
import time
from pathlib import Path

import numpy as np

from sources.buffer import FrameBuffer
from tests.core.flight_helpers import wait_until
from uav_tui.events import EventLog
from uav_tui.hosting.process_host import SubprocessHost

SPAWNER = '''
import multiprocessing, os, subprocess, sys, time
from multiprocessing import shared_memory
from pathlib import Path

def _sleep():
    time.sleep(600)

class Spawner:
    """Starts a helper process and a multiprocessing worker, and appends their pids to ``marker``; creates
    shared memory (left for multiprocessing's resource tracker to unlink) and writes its name to ``marker.shm``;
    F2 ends its own process, F4 hangs."""

    def __init__(self, marker):
        helper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
        self.worker = multiprocessing.get_context("fork").Process(target=_sleep)
        self.worker.start()
        with open(marker, "a") as pids:
            pids.write(f"{helper.pid} {self.worker.pid}\\n")
        self.scratch = shared_memory.SharedMemory(create=True, size=2**20)
        Path(marker + ".shm").write_text(self.scratch.name)

    def photo_processing(self, frame):
        pass

    def customize_processing(self, id):
        if id == 2:
            os._exit(3)
        if id == 4:
            time.sleep(60)
'''


def running(pid: int) -> bool:
    """Alive and not a zombie."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rpartition(")")[2].split()[0] != "Z"
    except FileNotFoundError:
        return False


def started(marker: Path) -> list[list[int]]:
    """The pids each construction of the processor started, in order."""
    return [[int(pid) for pid in line.split()] for line in marker.read_text().splitlines()] if marker.exists() else []


async def start_spawner(tmp_path: Path, **options: object) -> tuple[SubprocessHost, Path, list[str]]:
    (tmp_path / "spawner.py").write_text(SPAWNER)
    marker, faults = tmp_path / "pids", []
    worker = await SubprocessHost.start(f"{tmp_path}/spawner.py:Spawner", {"marker": str(marker)}, print,
                                       events=EventLog(), on_fault=faults.append, first_backoff_s=0.05, **options)
    return worker, marker, faults


async def test_stopping_the_platform_ends_the_processes_the_processor_started(tmp_path: Path) -> None:
    worker, marker, _ = await start_spawner(tmp_path)
    try:
        [helpers] = started(marker)
        assert all(running(pid) for pid in helpers)
    finally:
        worker.close()  # as quit and SIGTERM do
    await wait_until(lambda: not any(running(pid) for pid in helpers), 5, "the processor's helpers to end")
    scratch = Path("/dev/shm") / (tmp_path / "pids.shm").read_text().lstrip("/")
    await wait_until(lambda: not scratch.exists(), 5, "the processor's shared memory to be unlinked")


async def test_a_processor_killed_for_hanging_takes_what_it_started_with_it(tmp_path: Path) -> None:
    worker, marker, faults = await start_spawner(tmp_path, timeout_s=1.0)
    task = asyncio.create_task(worker.run())
    call = asyncio.create_task(worker.call("customize_processing", 4))
    try:
        await wait_until(lambda: len(started(marker)) == 2, 20, "the restarted processor")
        first, second = started(marker)
        assert not any(running(pid) for pid in first)  # killed with the hung processor ...
        assert all(running(pid) for pid in second)  # ... and the fresh one's are its own
        assert call.done() and "no answer for" in faults[0]
    finally:
        task.cancel()
        await asyncio.gather(task, call, return_exceptions=True)
    await wait_until(lambda: not any(running(pid) for pid in second), 5, "the restarted processor's helpers to end")


async def test_a_processor_that_dies_leaves_nothing_it_started_running(tmp_path: Path) -> None:
    worker, marker, faults = await start_spawner(tmp_path)
    buffer = FrameBuffer()
    worker.attach(buffer)
    task = asyncio.create_task(worker.run())
    try:
        buffer.put(np.zeros((8, 8, 3), np.uint8))
        [helpers] = started(marker)
        await asyncio.gather(worker.call("customize_processing", 2), return_exceptions=True)
        await wait_until(lambda: bool(faults), 5, "the death to be reported")
        reported = time.monotonic()
        await wait_until(lambda: not any(running(pid) for pid in helpers), 5, "its helpers to end")
        assert time.monotonic() - reported < 1.0 and "exited with code 3" in faults[0]
    finally:
        task.cancel()
        await asyncio.gather(task, return_exceptions=True)


async def test_an_idle_processor_killed_from_outside_is_reported_though_its_worker_holds_its_pipe(
        tmp_path: Path) -> None:
    """As the kernel's OOM killer would, while it waits for a frame: no call or frame pending makes it overdue, so
    only its end can tell (before, its forked worker kept the pipe open and nothing ever reported it)."""
    worker, marker, faults = await start_spawner(tmp_path)
    task = asyncio.create_task(worker.run())
    try:
        pid = worker.state().pid
        os.kill(pid, signal.SIGKILL)
        await wait_until(lambda: bool(faults), 2, "the death to be reported")
        assert faults == [f"processor (pid {pid}) killed by SIGKILL (out of memory? the kernel's OOM killer sends it)"]
        await wait_until(lambda: len(started(marker)) == 2 and worker.state().pid != pid, 20, "the restart")
    finally:
        task.cancel()
        await asyncio.gather(task, return_exceptions=True)
