"""``pyproject.toml`` as the build reads it (no deprecation warnings), and what the built wheel carries."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import tomllib
import warnings
import zipfile
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from setuptools.config.pyprojecttoml import apply_configuration
from setuptools.dist import Distribution

from processors.detection import DATA_DIR_ENV

ROOT = Path(__file__).resolve().parents[1]


def test_metadata_reads_without_warnings_and_the_license_is_an_spdx_expression(monkeypatch) -> None:
    monkeypatch.chdir(ROOT)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        distribution = apply_configuration(Distribution(), "pyproject.toml")
    assert distribution.metadata.license_expression == "MIT"


def test_the_build_asks_for_a_setuptools_that_reads_the_spdx_license() -> None:
    requires = tomllib.loads((ROOT / "pyproject.toml").read_text())["build-system"]["requires"]
    setuptools = next(Requirement(r) for r in requires if Requirement(r).name == "setuptools")
    assert not setuptools.specifier.contains("76.1.0") and setuptools.specifier.contains("77.0.0")  # PEP 639: 77


PACKAGES = ("uav_tui", "uav_values", "processors", "sources", "controllers")

INSTALLED_CHECK = """
import sys
from pathlib import Path

import cv2
import numpy as np
from skimage import data

import processors.models
from processors.opencv_tracker import OpenCVTracker
from processors.yolo_detector import YoloDetector

assert Path(processors.models.__file__).is_relative_to(sys.prefix), processors.models.__file__
image = cv2.cvtColor(data.astronaut(), cv2.COLOR_RGB2BGR)
nano = processors.models.create_nanotrack()
nano.init(image, (150, 30, 150, 180))
ok, box = nano.update(image)
assert ok and abs(box[0] - 150) < 20, box
baseline = OpenCVTracker("nano")  # cv:nano in uav-tui eval, without arguments
baseline.catch_cmd((150, 30, 150, 180))
baseline.photo_processing(image.copy())
assert baseline.box is not None
labels = {d.label for d in YoloDetector().backend.detect(image)}
assert "person" in labels, labels
print("models ok")
"""


@pytest.mark.timeout(300)
def test_the_models_load_from_the_installed_package_in_a_fresh_venv_without_the_shared_folder(tmp_path: Path) -> None:
    """Build the wheel, install it alone in a new venv, and load NanoTrack and Yolo-Fastest from there.

    The venv sees this one's site-packages for the dependencies only (a plain path in a ``.pth``: the
    editable install's finder there is not run), and runs in an empty folder with no ``shared/`` beside it.
    """
    source = tmp_path / "source"
    source.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, source / name)
    for package in PACKAGES:
        shutil.copytree(ROOT / package, source / package, ignore=shutil.ignore_patterns("__pycache__"))
    wheels, venv, work = tmp_path / "wheels", tmp_path / "venv", tmp_path / "work"
    work.mkdir()
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    subprocess.run([*pip, "wheel", "--no-deps", "--no-build-isolation", "--no-index", "-w", str(wheels), str(source)],
                   check=True, cwd=tmp_path)
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = venv / "bin" / "python"
    (wheel,) = wheels.glob("uav_tui-*.whl")
    with zipfile.ZipFile(wheel) as archive:  # PEP 561: type checkers use the packages' own annotations
        assert {f"{package}/py.typed" for package in PACKAGES} <= set(archive.namelist())
    subprocess.run([*pip, "--python", str(python), "install", "--no-deps", "--no-index", str(wheel)], check=True)
    site = Path(subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                               check=True, capture_output=True, text=True).stdout.strip())
    (site / "dependencies.pth").write_text(sysconfig.get_path("purelib") + "\n")
    env = {key: value for key, value in os.environ.items() if key not in ("PYTHONPATH", DATA_DIR_ENV)}
    run = subprocess.run([str(python), "-c", INSTALLED_CHECK], cwd=work, env=env, capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0 and "models ok" in run.stdout, run.stderr[-3000:]
