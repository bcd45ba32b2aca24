"""The URI factory: every scheme maps to an importable source, errors name what is wrong."""

from __future__ import annotations

import importlib

import pytest

from sources import SCHEMES, create_source
from uav_tui.errors import SourceUriError


@pytest.mark.parametrize("scheme", sorted(SCHEMES))
def test_every_scheme_names_a_class_with_from_uri(scheme: str) -> None:
    module_name, class_name = SCHEMES[scheme].split(":")
    cls = getattr(importlib.import_module(module_name), class_name)
    assert callable(cls.from_uri)


@pytest.mark.parametrize("uri, kind", [("usb:0", "usb"), ("picam:0", "picam"), ("rtsp://cam.local/s", "rtsp"),
                                       ("rtsps://cam.local/s", "rtsps"), ("http://cam.local/video.mjpg", "http"),
                                       ("https://cam.local/video.mjpg", "https"), ("sim:", "sim"),
                                       ("file:x.mp4", "file"), ("synthetic:", "synthetic")])
def test_kind_matches_the_scheme(uri: str, kind: str) -> None:
    assert create_source(uri).get_properties()["kind"] == kind


def test_platform_context_is_accepted_by_every_source() -> None:
    # The platform may pass pose_provider whatever the URI, e.g. when switching sources at run time.
    for uri in ("usb:0", "picam:0", "rtsp://cam.local/s", "file:x.mp4", "synthetic:", "sim:"):
        create_source(uri, pose_provider=lambda t_mono_ns: None)


def test_unknown_scheme_lists_the_known_ones() -> None:
    with pytest.raises(SourceUriError, match=r"unknown camera scheme 'webcam'.*usb:.*sim:"):
        create_source("webcam:0")
