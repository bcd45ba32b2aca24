"""``pyproject.toml`` as the build reads it: no deprecation warnings (they print on every install)."""

from __future__ import annotations

import tomllib
import warnings
from pathlib import Path

from packaging.requirements import Requirement
from setuptools.config.pyprojecttoml import apply_configuration
from setuptools.dist import Distribution

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
