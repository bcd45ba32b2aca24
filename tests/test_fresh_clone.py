"""A clone on a machine that has only the repository (no ``shared/`` beside it, no ``UAV_TUI_DATA_DIR``): the
suite that ``.ci/run`` runs collects without an error, and the tests that need the real-video set skip, saying how
to get it, and the run counts them at its end."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from processors.detection import DATA_DIR_ENV

ROOT = Path(__file__).resolve().parents[1]

DATA_ONLY = ["tests/processors/test_csrt_real_video.py", "tests/processors/test_nanotrack_real_video.py",
             "tests/core/test_bench_pipeline.py"]
"""Modules whose every test needs the real-video set."""


@pytest.fixture(scope="module")
def clone(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The repository's files as they are in this work tree (tracked ones only: no venv, runs or caches), copied
    into a fresh temporary folder."""
    if shutil.which("git") is None:
        pytest.skip("git is not installed: the test copies the files git tracks")
    listed = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=False)
    if listed.returncode != 0:
        pytest.skip(f"{ROOT} is not a git checkout: the test copies the files git tracks")
    target = tmp_path_factory.mktemp("fresh") / "uav-tui"
    for name in filter(None, listed.stdout.split(b"\0")):
        source = ROOT / os.fsdecode(name)
        if source.is_file():  # a tracked file deleted in the work tree is not in the clone either
            (target / os.fsdecode(name)).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, target / os.fsdecode(name))
    assert not any((parent / "shared" / "data").is_dir() for parent in target.parents), "data beside the clone"
    return target


def pytest_in(clone: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """pytest run in ``clone`` on its own code, as on a machine without the data (this venv's interpreter)."""
    env = {key: value for key, value in os.environ.items() if not key.startswith("PYTEST_") and key != DATA_DIR_ENV}
    env["PYTHONPATH"] = str(clone)
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", *args], cwd=clone, env=env,
                          capture_output=True, text=True, timeout=100, check=False)


@pytest.mark.timeout(240)
def test_a_clone_without_the_data_collects_every_test_ci_runs(clone: Path) -> None:
    # .ci/run's three steps take "not sitl and not serial and not soak", "serial and not sitl" and "soak and not
    # sitl": together, "not sitl"; every module is imported to collect any of them
    done = pytest_in(clone, "--collect-only", "-q", "-m", "not sitl")
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert " error" not in done.stdout.splitlines()[-1], done.stdout.splitlines()[-1]
    assert "tests/processors/test_csrt_real_video.py::" in done.stdout  # the data's tests are there, to be skipped


@pytest.mark.timeout(240)
def test_tests_that_need_the_data_skip_saying_how_to_get_it_and_are_counted(clone: Path) -> None:
    listed = pytest_in(clone, "--collect-only", "-q", *DATA_ONLY)
    tests = sum("::" in line for line in listed.stdout.splitlines())
    assert tests >= 10, listed.stdout[-2000:]
    done = pytest_in(clone, "-q", *DATA_ONLY)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert f"{tests} skipped" in done.stdout.splitlines()[-1], done.stdout[-2000:]
    summary = [line for line in done.stdout.splitlines() if "skipped for want of data" in line]
    assert summary and summary[0].startswith(f"{tests} tests skipped for want of data: "), done.stdout[-2000:]
    assert DATA_DIR_ENV in summary[0] and "docs/evaluation.md#" in summary[0]
