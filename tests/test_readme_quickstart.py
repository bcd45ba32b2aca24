"""The README's quick start, pasted in order: every ``uav-tui`` command in it runs (with a short ``--duration``)."""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DURATION_S = "4"


def quick_start_lines() -> list[str]:
    """The commands of the first fenced block under ``## Quick start``, comments removed."""
    readme = (ROOT / "README.md").read_text()
    section = readme.split("\n## Quick start\n", 1)[1]
    block = re.search(r"```bash\n(.*?)```", section, re.S)
    assert block is not None, "the quick start has no ```bash block"
    return [line.split("  #", 1)[0].strip() for line in block.group(1).splitlines() if line.strip()]


def test_the_venv_is_set_up_and_activated_before_the_first_uav_tui_command() -> None:
    lines = quick_start_lines()
    first = next(i for i, line in enumerate(lines) if line.startswith("uav-tui"))
    assert lines[:first] == ["bash scripts/setup.sh", "source .venv/bin/activate"]


def _in_a_terminal(command: list[str], env: dict[str, str], tmp_path: Path) -> int:
    """Run ``command`` in an 80x24 tmux terminal (the dashboard needs one); its exit status."""
    socket, status = str(tmp_path / "tmux.sock"), tmp_path / "status"
    exports = " ".join(f"{key}={shlex.quote(env[key])}" for key in ("PATH", "UAV_TUI_CONFIG"))
    script = f"cd {shlex.quote(str(ROOT))}; env {exports} TERM=xterm-256color {shlex.join(command)}; echo $? > {status}"
    subprocess.run(["tmux", "-S", socket, "new-session", "-d", "-x", "80", "-y", "24", f"sh -c {shlex.quote(script)}"],
                   check=True, timeout=10)
    try:
        deadline = time.monotonic() + 90
        while not (status.exists() and status.read_text().strip()) and time.monotonic() < deadline:
            time.sleep(0.2)
        return int(status.read_text())
    finally:
        subprocess.run(["tmux", "-S", socket, "kill-server"], capture_output=True, timeout=10)


@pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed (the dashboard needs a terminal)")
def test_every_quick_start_command_runs(tmp_path: Path) -> None:
    config = tmp_path / "uav.toml"
    config.write_text(f'[recording]\nruns_dir = "{tmp_path / "runs"}"\n')
    # What `source .venv/bin/activate` does for uav-tui: the venv's bin first on PATH.
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}",
           "UAV_TUI_CONFIG": str(config)}
    outputs = {}
    for line in quick_start_lines():
        if not line.startswith("uav-tui"):
            continue
        command = shlex.split(line)
        if command[1] not in ("runs", "report", "sim"):
            command += ["--duration", DURATION_S]
        if "--no-ui" in command or command[1] in ("runs", "report"):
            result = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
            assert result.returncode == 0, f"{line}\n{result.stdout[-2000:]}\n{result.stderr[-2000:]}"
            outputs[command[1]] = result.stdout
        else:
            assert _in_a_terminal(command, env, tmp_path) == 0, line
    runs = sorted((tmp_path / "runs").iterdir())
    assert len(runs) == sum(line.startswith("uav-tui") and shlex.split(line)[1].startswith("-")
                            for line in quick_start_lines())
    assert all(run.name in outputs["runs"] for run in runs)
    assert (runs[-1] / "report.html").is_file() and f"wrote {runs[-1] / 'report.html'}" in outputs["report"]
