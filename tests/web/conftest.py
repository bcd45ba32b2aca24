"""Fixtures for the web page tests: a core on loopback with the page on, a recording processor."""

from __future__ import annotations

import signal
import socket
import subprocess
import threading
from collections.abc import AsyncIterator
from typing import Any

import cv2
import pytest

from controllers.sim.launcher import free_ports
from uav_tui.config import load_config
from uav_tui.core import UavCore

TOKEN = "pYx3Qm-8Kd2vRw7TzL0bNc5Hj9Fs4GaE"
"""A token the configuration accepts (as ``secrets.token_urlsafe(24)`` makes them)."""


class RecordingProcessor:
    """Draws a marker (the overlay) on every frame and records the operator's calls.

    Its ``box`` (what it "tracks") is the last ROI moved 10 px right and down, so a test can tell it
    from the selection.
    """

    def __init__(self) -> None:
        self.tmMgr = None
        self.rois: list[tuple[int, int, int, int]] = []
        self.buttons: list[int] = []
        self.frames = 0
        self.box: tuple[int, int, int, int] | None = None
        self._lock = threading.Lock()

    def photo_processing(self, frame: Any) -> None:
        self.frames += 1
        cv2.rectangle(frame, (20, 20), (140, 60), (0, 255, 255), -1)
        cv2.putText(frame, f"#{self.frames}", (26, 52), cv2.FONT_HERSHEY_SIMPLEX, 0.9, (0, 0, 0), 2)

    def catch_cmd(self, roi: tuple[int, int, int, int]) -> None:
        with self._lock:
            self.rois.append(roi)
        x, y, w, h = roi
        self.box = (x + 10, y + 10, w, h)

    def customize_processing(self, id: int) -> None:  # noqa: A002 - the published name
        with self._lock:
            self.buttons.append(id)


def interrupt(process: subprocess.Popen[bytes], timeout_s: float = 20.0) -> None:
    """Stop a platform started by a test as Ctrl-C does; kill it if it has not ended within ``timeout_s``."""
    process.send_signal(signal.SIGINT)
    try:
        process.wait(timeout_s)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


def free_port(kind: socket.SocketKind = socket.SOCK_STREAM) -> int:
    return free_ports(1, kind)[0]


def make_core(**overrides: Any) -> UavCore:
    settings = {"source": "synthetic:", "fc": "none", "processor": "tests.web.conftest:RecordingProcessor",
                "record": False, "web": True, "web_host": "127.0.0.1", "web_port": free_port(),
                "web_token": TOKEN, "isolation": "thread", **overrides}  # processor_of() reads the object
    return UavCore(load_config(None, settings))


@pytest.fixture
async def web_core() -> AsyncIterator[UavCore]:
    """A running core (synthetic camera, no vehicle) serving the page on 127.0.0.1."""
    core = make_core()
    await core.start()
    try:
        yield core
    finally:
        await core.stop("test finished")


def processor_of(core: UavCore) -> RecordingProcessor:
    assert core.worker is not None
    return core.worker.processor.instance
