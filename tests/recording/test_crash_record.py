"""A segfault in the platform's own process (native code run with ``isolation = "thread"``) leaves the stacks of
every thread in the run folder, and ``uav-tui report`` / ``uav-tui runs`` say where the run died."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

SEGFAULTING = """\
import ctypes


class Segfaulting:
    def photo_processing(self, frame):
        pass

    def customize_processing(self, id):
        ctypes.string_at(0)  # line 9: reads address 0 in native code
"""


def uav(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "uav_tui", *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=60)


def test_a_segfault_in_the_platform_process_is_recorded_with_its_stack(tmp_path: Path) -> None:
    (tmp_path / "mine.py").write_text(SEGFAULTING)
    (tmp_path / "f1.txt").write_text("f 1\n")
    result = uav("--no-ui", "--fc", "none", "--source", "synthetic:", "--isolation", "thread", "--processor",
                 "mine.py:Segfaulting", "--script", "f1.txt", "--duration", "20", cwd=tmp_path)
    assert result.returncode == -signal.SIGSEGV, result.stderr
    run = next((tmp_path / "runs").iterdir())
    stacks = (run / "crash.txt").read_text()
    assert stacks.startswith("Fatal Python error: Segmentation fault")
    assert f'File "{tmp_path / "mine.py"}", line 9 in customize_processing' in stacks
    report = uav("report", str(run), cwd=tmp_path)
    assert report.returncode == 0, report.stderr
    assert ("the process crashed: Fatal Python error: Segmentation fault in string_at (" in report.stdout
            and f"called from customize_processing ({tmp_path / 'mine.py'}:9); crash.txt has every thread's stack"
            in report.stdout), report.stdout
    assert uav("runs", cwd=tmp_path).stdout.rstrip().endswith("(crashed)")


def test_a_run_that_ends_normally_leaves_no_crash_file(tmp_path: Path) -> None:
    result = uav("--no-ui", "--fc", "none", "--source", "synthetic:", "--duration", "2", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    run = next((tmp_path / "runs").iterdir())
    assert not (run / "crash.txt").exists()
    assert not uav("runs", cwd=tmp_path).stdout.rstrip().endswith(")")  # neither crashed nor left open
