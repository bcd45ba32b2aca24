"""Fixtures for the source tests: generated videos, loopback stream servers, the Picamera2 stand-in."""

from __future__ import annotations

import sys
import types
from collections.abc import Callable, Iterator
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.sources.picamera2_standin import Picamera2StandIn
from tests.sources.stream_servers import MjpegTestServer, RtspTestServer

VideoFactory = Callable[..., Path]


def create_video_file(path: Path, *, frames: int = 30, width: int = 160, height: int = 120, fps: float = 15.0,
                      fourcc: str = "mp4v") -> Path:
    """Write a clip whose frame ``i`` shows a white bar at column ``8 * i`` on a textured background."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*fourcc), fps, (width, height))
    assert writer.isOpened(), f"cannot write {path}"
    rng = np.random.default_rng(1)
    background = cv2.resize(rng.integers(0, 200, size=(height // 8, width // 8, 3), dtype=np.uint8),
                            (width, height), interpolation=cv2.INTER_CUBIC)
    for i in range(frames):
        image = background.copy()
        x = (8 * i) % (width - 8)
        image[:, x:x + 8] = 255
        writer.write(image)
    writer.release()
    return path


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
