"""Fixtures for the source tests: generated videos, loopback stream servers, the Picamera2 stand-in."""

from __future__ import annotations

import sys
import types
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from tests.sources.picamera2_standin import Picamera2StandIn
from tests.sources.stream_servers import MjpegTestServer, RtspTestServer
from tests.videos import create_video_file

VideoFactory = Callable[..., Path]


@pytest.fixture
def video_file(tmp_path: Path) -> VideoFactory:
    """``video_file(name="clip.mp4", frames=..., fps=..., ...)`` writes a clip into tmp_path."""

    def make(name: str = "clip.mp4", **options: object) -> Path:
        return create_video_file(tmp_path / name, **options)  # type: ignore[arg-type]

    return make


@pytest.fixture
def picamera2_standin(monkeypatch: pytest.MonkeyPatch) -> type[Picamera2StandIn]:
    """Makes ``from picamera2 import Picamera2`` return the stand-in class."""
    module = types.ModuleType("picamera2")
    module.Picamera2 = Picamera2StandIn  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "picamera2", module)
    Picamera2StandIn.instances.clear()
    monkeypatch.setattr(Picamera2StandIn, "frames_before_stall", [])
    return Picamera2StandIn


@pytest.fixture
def rtsp_server() -> Iterator[RtspTestServer]:
    server = RtspTestServer()
    server.start()
    yield server
    server.stop()


@pytest.fixture
def mjpeg_server() -> Iterator[MjpegTestServer]:
    server = MjpegTestServer()
    server.start()
    yield server
    server.stop()


@pytest.fixture
def fast_retry(monkeypatch: pytest.MonkeyPatch) -> None:
    """Shorter reconnect back-off so recovery tests take a fraction of a second per attempt."""
    monkeypatch.setattr("sources.base.RETRY_DELAYS_S", (0.05, 0.1, 0.2))
