"""``scripts/setup.sh``: what it installs, and that it does nothing when nothing changed.

The script runs for real on a copy of the repository's files; ``.venv/bin/python`` there is a stand-in
that records how it was called (the real installation is what ``.ci/run`` does on every CI run).
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

STAND_IN_PYTHON = """#!/usr/bin/env bash
bin="$(dirname "$0")"
echo "$*" >> "$bin/../calls.log"
if [ "$3" = install ] && [ "$5" = -e ]; then touch "$bin/uav-tui" && chmod +x "$bin/uav-tui"; fi
if [ "$1" = scripts/check_opencv.py ] && [ -e "$bin/../opencv-broken" ]; then exit 1; fi
exit 0
"""


def _checkout(tmp_path: Path) -> Path:
    (tmp_path / "scripts").mkdir()
    shutil.copy(ROOT / "scripts" / "setup.sh", tmp_path / "scripts" / "setup.sh")
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    python = tmp_path / ".venv" / "bin" / "python"
    python.parent.mkdir(parents=True)
    python.write_text(STAND_IN_PYTHON)
    python.chmod(0o755)
    return tmp_path


def _setup(repo: Path, *args: str) -> list[str]:
    """Run setup.sh; the installs it made (pip install lines)."""
    log = repo / ".venv" / "calls.log"
    before = log.read_text().splitlines() if log.exists() else []
    result = subprocess.run(["bash", "scripts/setup.sh", *args], cwd=repo, capture_output=True, text=True,
                            timeout=60)
    after = log.read_text().splitlines() if log.exists() else []
    assert result.returncode == 0 or "opencv" in result.stderr + str(after), result.stderr
    return [line for line in after[len(before):] if line.startswith("-m pip install -q -e")]


def test_runtime_only_by_default_test_tools_on_request(tmp_path: Path) -> None:
    repo = _checkout(tmp_path)
    assert _setup(repo) == ["-m pip install -q -e ."]
    assert _setup(repo, "dev") == ["-m pip install -q -e .[dev]"]


def test_nothing_changed_means_nothing_installed(tmp_path: Path) -> None:
    repo = _checkout(tmp_path)
    _setup(repo, "dev")
    assert _setup(repo, "dev") == []
    assert _setup(repo) == []  # the dev install contains the runtime one
    with (repo / "pyproject.toml").open("a") as pyproject:
        pyproject.write("\n# a new dependency\n")
    assert _setup(repo) == ["-m pip install -q -e ."]
    assert _setup(repo) == []
    assert _setup(repo, "dev") == ["-m pip install -q -e .[dev]"]


def test_a_failed_setup_is_redone(tmp_path: Path) -> None:
    repo = _checkout(tmp_path)
    (repo / ".venv" / "opencv-broken").touch()
    _setup(repo)
    (repo / ".venv" / "opencv-broken").unlink()
    assert _setup(repo) == ["-m pip install -q -e ."]
    assert _setup(repo) == []
