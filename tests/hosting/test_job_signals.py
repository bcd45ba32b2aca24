"""A Ctrl-Z, Ctrl-C or hang-up sent to the terminal's job while the platform starts a process.

Between fork and exec the new process has default handlers: before, a Ctrl-Z stopped it there and left uav-tui
waiting for it in the kernel (state D, not even SIGKILL ends it) until ``fg``; the vehicle was not flown. CI
caught it as ``test_ctrl_z_does_not_suspend_a_headless_run`` timing out: the run's ``uname -p``.
"""

from __future__ import annotations

import os
import platform
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

from tests.core.flight_helpers import wait_until
from uav_tui.events import EventLog
from uav_tui.hosting.frame_ring import job_signals_blocked
from uav_tui.hosting.process_host import SubprocessHost
from uav_tui.recording import run_info

ROOT = Path(__file__).resolve().parents[2]

SPAWNS_UNDER_CTRL_Z = '''
import os, signal, subprocess, sys
from uav_tui.hosting.frame_ring import job_signals_blocked
signal.signal(signal.SIGTSTP, lambda *_: None)  # as the platform's loop catches it
print("ready", flush=True)
for _ in range(100):
    with job_signals_blocked():
        subprocess.Popen(["true"]).wait()
os._exit(0)  # at a normal exit the handlers are reset first, and the next Ctrl-Z would stop it there
'''


def test_processes_started_while_the_job_gets_ctrl_z_start_and_the_starter_goes_on() -> None:
    """Without the block, 100 starts under a Ctrl-Z every 2 ms hung within a second (measured: every run)."""
    with subprocess.Popen([sys.executable, "-c", SPAWNS_UNDER_CTRL_Z], process_group=0, stdout=subprocess.PIPE,
                          text=True, env={**os.environ, "PYTHONPATH": str(ROOT)}) as job:
        try:
            assert job.stdout is not None and job.stdout.readline() == "ready\n"
            deadline = time.monotonic() + 60
            while job.poll() is None and time.monotonic() < deadline:
                os.killpg(job.pid, signal.SIGTSTP)
                time.sleep(0.002)
            states = [p.status() for p in psutil.Process(job.pid).children()] if job.poll() is None else []
            assert job.returncode == 0, f"hung: children {states}"
        finally:
            if job.poll() is None:
                os.killpg(job.pid, signal.SIGCONT)
                job.kill()

def test_the_block_is_undone_in_this_thread_after_the_start() -> None:
    before = signal.pthread_sigmask(signal.SIG_BLOCK, set())
    with job_signals_blocked():
        assert signal.SIGTSTP in signal.pthread_sigmask(signal.SIG_BLOCK, set())
    assert signal.pthread_sigmask(signal.SIG_BLOCK, set()) == before


async def test_the_processors_process_unblocks_the_job_signals_once_started(tmp_path: Path) -> None:
    """It inherits the block; left so, any process it starts would keep it too."""
    (tmp_path / "idle.py").write_text("class Idle:\n    def photo_processing(self, frame):\n        pass\n")
    worker = await SubprocessHost.start(f"{tmp_path}/idle.py:Idle", {}, print, events=EventLog(), on_fault=print)
    try:
        child = next(p for p in psutil.Process().children() if "uav_tui.hosting.child" in p.cmdline())

        def blocked() -> int:
            status = Path(f"/proc/{child.pid}/status").read_text()
            return int(next(line for line in status.splitlines() if line.startswith("SigBlk:")).split()[1], 16)

        job_bits = sum(1 << (int(sig) - 1) for sig in (signal.SIGTSTP, signal.SIGINT, signal.SIGHUP))
        await wait_until(lambda: not blocked() & job_bits, 10, "the job signals unblocked in the processor's process")
    finally:
        worker.close()


def test_a_runs_versions_start_no_process(monkeypatch: pytest.MonkeyPatch) -> None:
    """``platform.platform()`` runs ``uname -p``: the process a Ctrl-Z caught. The same text without it."""
    expected = platform.platform()

    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError(f"a process was started: {args}")

    monkeypatch.setattr(platform, "_uname_cache", None)  # as in a new process: the processor not yet asked
    monkeypatch.setattr(platform, "_platform_cache", {})
    monkeypatch.setattr(subprocess, "Popen", refuse)
    assert run_info.versions()["platform"] == expected
