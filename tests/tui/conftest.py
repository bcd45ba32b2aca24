"""Fixtures for the dashboard tests: a core on the synthetic camera, the app around it, waiting helpers."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from textual.pilot import Pilot

from uav_tui.config import Config, load_config
from uav_tui.core import UavCore
from uav_tui.tui.app import UavApp

HERE = Path(__file__).parent
RECORDING = f"{HERE / 'procs.py'}:RecordingProcessor"
"""The test processor that remembers F-keys and ROIs, loaded from its file."""


@pytest.fixture
def make_config(tmp_path: Path) -> Callable[..., Config]:
    """``make_config(fc="sim", ...)``: synthetic camera, the recording processor, nothing written to the repo."""
    def make(**overrides: Any) -> Config:
        # isolation "thread": these tests read what the processor object received (process isolation has
        # its own tests in tests/hosting/test_isolation.py).
        values = {"source": "synthetic:?fps=30", "processor": RECORDING, "fc": "none", "record": False,
                  "runs_dir": str(tmp_path / "runs"), "isolation": "thread", **overrides}
        return load_config(None, values)
    return make


@pytest.fixture
def make_app(make_config: Callable[..., Config]) -> Callable[..., UavApp]:
    def make(**overrides: Any) -> UavApp:
        return UavApp(UavCore(make_config(**overrides)))
    return make


async def wait_for(pilot: Pilot, condition: Callable[[], Any], timeout: float = 10.0, what: str = "") -> Any:
    """Let the app run until ``condition()`` is truthy; fail after ``timeout`` seconds (generous: CI is slow)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        result = condition()
        if result:
            return result
        await pilot.pause(0.05)
    pytest.fail(f"timed out waiting for {what or condition}")


async def started(pilot: Pilot) -> UavApp:
    """Wait until the app's core runs and the first frame was processed."""
    app = pilot.app
    assert isinstance(app, UavApp)
    await wait_for(pilot, lambda: app.core.worker is not None and app.core.worker.last is not None,
                   what="the first processed frame")
    await pilot.pause(0.1)
    return app


def in_log(app: UavApp, text: str) -> bool:
    """Whether the event log widget shows ``text`` (compared without whitespace: the log wraps lines)."""
    shown = "".join(strip.text for strip in app.query_one("#events").lines)
    return "".join(text.split()) in "".join(shown.split())
