"""A disk that fills up during a run, for real: said once with what was lost, the run closed, a non-zero exit status.

The run folder is on a 2 MB tmpfs the test mounts (as root), else the platform runs under a 512 KB file-size limit
(``RLIMIT_FSIZE``: its writes past it fail as a full disk's do, with EFBIG instead of ENOSPC).
"""

from __future__ import annotations

import contextlib
import json
import os
import resource
import signal
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


@contextlib.contextmanager
def small_filesystem(path: Path) -> Iterator[Callable[[], None] | None]:
    """``path`` made a 2 MB tmpfs (yields None), or, where mounting is not permitted, what limits a process's files to
    512 KB (a ``preexec_fn``)."""
    path.mkdir()
    mounted = os.geteuid() == 0 and subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(path)],
                                                   capture_output=True).returncode == 0
    try:
        yield None if mounted else _file_size_limit
    finally:
        if mounted:
            subprocess.run(["umount", "-l", str(path)], check=True)


def _file_size_limit() -> None:
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # the write then fails with EFBIG instead of killing the process
    resource.setrlimit(resource.RLIMIT_FSIZE, (512 * 1024, 512 * 1024))


def test_a_full_disk_is_said_once_the_run_is_closed_and_the_exit_status_says_so(tmp_path: Path) -> None:
    runs = tmp_path / "small"
    with small_filesystem(runs) as limit:
        result = subprocess.run(
            [sys.executable, "-m", "uav_tui", "--no-ui", "--fc", "none", "--processor", "template",
             "--source", "synthetic:?width=640&height=480", "--runs-dir", str(runs), "--min-free-mb", "0",
             "--record-every", "1", "--duration", "8"],
            cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True, timeout=90,
            preexec_fn=limit)
        output = result.stdout + result.stderr
        run_dir = next(runs.iterdir())
        info = json.loads((run_dir / "run.json").read_text())
        left = sorted(p.name for p in run_dir.iterdir())
    # Before: a 14-line traceback per frame, the writer thread dead, run.json's end never written (a 0-byte
    # run.json.tmp left) and exit status 0.
    assert output.count("Traceback") <= 1, output[:5000]
    assert output.count("[error] recorder:") <= 3, output[:5000]  # the first drop of each kind, and the summary
    assert result.returncode == 5, output[-3000:]
    assert "the run is incomplete: " in output and "could not be written" in output, output[-3000:]
    assert "end_wall_ns" in info and info["recording"]["lost"], info.get("recording")  # closed, with the losses
    assert "run.json.tmp" not in left and not any(name.startswith(".") for name in left), left
