"""The disk space a run holds for its last write: freed at its end, and, when its process was killed, at the next
start under the same runs folder; a run going on in another process keeps its own."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

from uav_tui.config import RecordingConfig
from uav_tui.recording.recorder import Recorder
from uav_tui.recording.reserve import RESERVE, RESERVE_BYTES

ROOT = Path(__file__).resolve().parents[2]

OPEN_A_RUN = """
import os, signal, sys
from uav_tui.config import RecordingConfig
from uav_tui.recording.recorder import Recorder
recorder = Recorder.open(RecordingConfig(runs_dir=sys.argv[1]), {}, telemetry_expected=False)
print(recorder.run_dir, flush=True)
if sys.argv[2] == "kill":
    os.kill(os.getpid(), signal.SIGKILL)
sys.stdin.read()  # a run going on until the test closes stdin
recorder.close()
"""


def _open_run(runs: Path, how: str) -> tuple[subprocess.Popen[str], Path]:
    process = subprocess.Popen([sys.executable, "-c", OPEN_A_RUN, str(runs), how], stdin=subprocess.PIPE,
                               stdout=subprocess.PIPE, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert process.stdout is not None
    return process, Path(process.stdout.readline().strip())


def test_a_killed_runs_reserve_is_freed_at_the_next_start_and_a_live_runs_is_kept(tmp_path: Path) -> None:
    killed, killed_dir = _open_run(tmp_path, "kill")
    with killed:
        assert killed.wait(30) == -signal.SIGKILL
    assert (killed_dir / RESERVE).stat().st_size == RESERVE_BYTES  # what SIGKILL leaves behind
    live, live_dir = _open_run(tmp_path, "stay")
    with live:
        recorder = Recorder.open(RecordingConfig(runs_dir=str(tmp_path)), {}, telemetry_expected=False)
        assert not (killed_dir / RESERVE).exists()
        assert (live_dir / RESERVE).stat().st_size == RESERVE_BYTES
        assert (recorder.run_dir / RESERVE).stat().st_size == RESERVE_BYTES
        recorder.close()
        assert not (recorder.run_dir / RESERVE).exists()
        live.communicate("", timeout=30)
    assert live.returncode == 0 and not (live_dir / RESERVE).exists()
