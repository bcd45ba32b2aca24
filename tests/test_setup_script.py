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
echo "python $*" >> "$bin/../calls.log"
if [ "$*" = "-m pip install -q --disable-pip-version-check uv" ]; then cp "$bin/uv.stand-in" "$bin/uv"; fi
if [ "$1" = scripts/check_opencv.py ] && [ -e "$bin/../opencv-broken" ]; then exit 1; fi
exit 0
"""
"""The venv's python: pip installs the stand-in uv."""

STAND_IN_UV = """#!/usr/bin/env bash
bin="$(dirname "$0")"
echo "uv $*" >> "$bin/../calls.log"
if [ "$1 $2" = "pip install" ]; then touch "$bin/uav-tui" && chmod +x "$bin/uav-tui"; fi
exit 0
"""
"""uv: installing the project makes its entry point."""


def _checkout(tmp_path: Path) -> Path:
    (tmp_path / "scripts").mkdir()
    shutil.copy(ROOT / "scripts" / "setup.sh", tmp_path / "scripts" / "setup.sh")
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    python = tmp_path / ".venv" / "bin" / "python"
    python.parent.mkdir(parents=True)
    for name, script in (("python", STAND_IN_PYTHON), ("uv.stand-in", STAND_IN_UV)):
        (python.parent / name).write_text(script)
        (python.parent / name).chmod(0o755)
    return tmp_path


def _setup(repo: Path, *args: str) -> list[str]:
    """Run setup.sh; the installs of the project it made (what followed ``-e``)."""
    log = repo / ".venv" / "calls.log"
    before = log.read_text().splitlines() if log.exists() else []
    result = subprocess.run(["bash", "scripts/setup.sh", *args], cwd=repo, capture_output=True, text=True,
                            timeout=60)
    after = log.read_text().splitlines() if log.exists() else []
    assert result.returncode == 0 or "opencv" in result.stderr + str(after), result.stderr
    prefix = "uv pip install -q --python .venv/bin/python -e "
    return [line.removeprefix(prefix) for line in after[len(before):] if line.startswith(prefix)]


def test_runtime_only_by_default_test_tools_on_request(tmp_path: Path) -> None:
    repo = _checkout(tmp_path)
    assert _setup(repo) == ["."]
    assert _setup(repo, "dev") == [".[dev]"]


def test_nothing_changed_means_nothing_installed(tmp_path: Path) -> None:
    repo = _checkout(tmp_path)
    _setup(repo, "dev")
    assert _setup(repo, "dev") == []
    assert _setup(repo) == []  # the dev install contains the runtime one
    with (repo / "pyproject.toml").open("a") as pyproject:
        pyproject.write("\n# a new dependency\n")
    assert _setup(repo) == ["."]
    assert _setup(repo) == []
    assert _setup(repo, "dev") == [".[dev]"]


def test_a_failed_setup_is_redone(tmp_path: Path) -> None:
    repo = _checkout(tmp_path)
    (repo / ".venv" / "opencv-broken").touch()
    _setup(repo)
    (repo / ".venv" / "opencv-broken").unlink()
    assert _setup(repo) == ["."]
    assert _setup(repo) == []
