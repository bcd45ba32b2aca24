"""``warm_up_source``: a source's slow one-off preparation, done ahead of opening it (the platform overlaps it
with connecting the vehicle); mistakes in the URI are left for ``open_source`` to report."""

from __future__ import annotations

import importlib

import pytest

from sources import SCHEMES, open_source, warm_up_source
from sources.base import WarmsUp
from sources.ground import default_ground


def test_the_sim_camera_builds_its_ground_ahead_and_uses_that_one() -> None:
    default_ground.cache_clear()
    warm_up_source("sim:?seed=3&width=64&height=48")
    assert default_ground.cache_info().currsize == 1
    source = open_source("sim:?seed=3&width=64&height=48")
    try:
        assert source.buffer.wait_newer(0, 30) is not None, "no frame"
        assert source.renderer is not None and source.renderer.ground is default_ground(3)
        assert default_ground.cache_info().misses == 1  # built once, by the warm-up
    finally:
        source.close()


@pytest.mark.parametrize("uri", ["nope:", "sim:?seed=x", "no scheme", "synthetic:"])
def test_nothing_to_prepare_or_a_bad_uri_is_silent(uri: str) -> None:
    warm_up_source(uri)


def test_only_the_sim_camera_has_a_warm_up() -> None:
    for scheme, target in SCHEMES.items():
        module_name, class_name = target.split(":")
        if scheme == "picam":
            continue  # imports picamera2
        cls = getattr(importlib.import_module(module_name), class_name)
        assert isinstance(cls, WarmsUp) == (scheme == "sim"), scheme
