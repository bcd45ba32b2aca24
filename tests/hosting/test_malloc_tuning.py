"""The allocator settings for per-frame images: heap memory freed by one frame is there for the next."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from uav_tui.hosting.malloc_tuning import ENVIRONMENT, child_environment

ROOT = Path(__file__).resolve().parents[2]

FRAMES = '''
import resource, sys
import numpy as np
from uav_tui.hosting.malloc_tuning import tune_this_process
if sys.argv[1] == "tuned":
    assert tune_this_process()
def frame():  # a detector's frame: three 6 MB temporaries alive together, all freed at its end
    a = np.ones(6 << 20, np.uint8); b = a + 1; c = b * 2
    return int(c[-1])
for _ in range(3):
    frame()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(10):
    frame()
print((resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before) / 10)
'''


def page_faults_per_frame(mode: str) -> float:
    env = {name: value for name, value in os.environ.items() if not name.startswith("MALLOC_")}
    env["PYTHONPATH"] = str(ROOT)
    run = subprocess.run([sys.executable, "-c", FRAMES, mode], env=env, capture_output=True, text=True, timeout=60,
                         check=True)
    return float(run.stdout)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's allocator")
def test_a_tuned_process_does_not_fault_its_frame_memory_in_again_every_frame() -> None:
    default, tuned = page_faults_per_frame("default"), page_faults_per_frame("tuned")
    assert default > 1000  # a 6 MB temporary (1536 pages of 4 KB) is given back and faulted in anew every frame
    assert tuned < default / 20


def test_the_users_own_malloc_settings_win() -> None:
    assert child_environment({"PATH": "/bin"}) == {"PATH": "/bin", **ENVIRONMENT}
    mine = {"MALLOC_ARENA_MAX": "2"}
    assert child_environment(mine) == mine
    tunables = {"GLIBC_TUNABLES": "glibc.malloc.trim_threshold=1"}
    assert child_environment(tunables) == tunables

