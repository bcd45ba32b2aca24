"""OpenCV's thread pool in the processor's process: idle workers soon sleep instead of spinning for a millisecond."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from uav_tui.config import load_config
from uav_tui.core import UavCore
from uav_tui.hosting import malloc_tuning, opencv_pool

JOBS = '''
import os, time
import cv2, numpy as np
image = np.zeros((480, 640, 3), np.uint8)
def workers_cpu_s():  # on-CPU time of every thread but this one, to the nanosecond
    main, total = str(os.getpid()), 0
    for tid in os.listdir("/proc/self/task"):
        if tid != main:
            with open(f"/proc/self/task/{tid}/schedstat") as schedstat:
                total += int(schedstat.read().split()[0])
    return total / 1e9
cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)  # the pool is started
before = workers_cpu_s()
for _ in range(100):  # a processor's frames: a parallel job, then a wait for the next frame
    cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    time.sleep(0.005)
print(workers_cpu_s() - before)
'''


def workers_cpu_s(environ: dict[str, str]) -> float:
    """CPU seconds OpenCV's worker threads spend over 100 small jobs 5 ms apart.

    Without OpenBLAS's threads: they spin for a tenth of a second after the import, whatever OpenCV does.
    """
    env = {name: value for name, value in os.environ.items() if not name.startswith("OPENCV_THREAD_POOL_")}
    env["OPENBLAS_NUM_THREADS"] = "1"
    run = subprocess.run([sys.executable, "-c", JOBS], env={**env, **environ}, capture_output=True, text=True,
                         timeout=60, check=True)
    return float(run.stdout)


@pytest.mark.skipif(not sys.platform.startswith("linux") or (os.cpu_count() or 1) < 2,
                    reason="per-thread CPU time from Linux /proc; OpenCV starts no worker on one core")
def test_idle_workers_sleep_with_the_settings() -> None:
    spinning, sleeping = workers_cpu_s({}), workers_cpu_s(opencv_pool.ENVIRONMENT)
    if spinning < 0.03:  # OpenCV's default spins ~0.8 ms a job on an idle core, yielding it to anything runnable
        pytest.skip(f"the cores are busy: OpenCV's spinning workers used only {spinning * 1e3:.1f} ms")
    assert sleeping < spinning / 3


def test_the_users_own_pool_settings_win() -> None:
    assert opencv_pool.child_environment({"PATH": "/bin"}) == {"PATH": "/bin", **opencv_pool.ENVIRONMENT}
    mine = opencv_pool.child_environment({"OPENCV_THREAD_POOL_ACTIVE_WAIT_WORKER": "500"})
    assert mine == {**opencv_pool.ENVIRONMENT, "OPENCV_THREAD_POOL_ACTIVE_WAIT_WORKER": "500"}


async def test_the_processors_process_starts_with_the_allocator_and_pool_settings(tmp_path: Path) -> None:
    core = UavCore(load_config(None, {"source": "synthetic:", "processor": "template", "fc": "none",
                                      "record": False, "isolation": "process", "runs_dir": str(tmp_path)}))
    await core.start()
    try:
        pid = core.worker.state().pid
        environ = dict(entry.split("=", 1) for entry in Path(f"/proc/{pid}/environ").read_text().split("\0") if entry)
    finally:
        await core.stop()
    expected = {**malloc_tuning.ENVIRONMENT, **opencv_pool.ENVIRONMENT}
    assert {name: environ.get(name) for name in expected} == expected
