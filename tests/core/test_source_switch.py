"""Switching the camera at run time keeps the processor, the flight-controller link and the flight going."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.core.flight_helpers import flying_core, wait_until
from uav_tui.camera.active import CameraKind
from uav_tui.errors import SourceError


async def test_switching_sources_keeps_processor_and_link(tmp_path: Path) -> None:
    async with flying_core(tmp_path) as core:
        pid = core.worker.state().pid  # the processor's own process: the same one throughout
        controller = core.controller
        await core.execute("f 1")  # the steering processor now streams vectors (autonomy stays off)
        for uri in ("sim:?width=320&height=240", "synthetic:?width=200&height=100&seed=3"):
            processed = core.worker.stats.frames_processed
            message = await core.execute(f"source {uri}")
            assert uri in message
            await wait_until(lambda p=processed: core.worker.stats.frames_processed > p + 10, 30, f"frames from {uri}")
            assert core.status().source_uri == uri
            assert core.worker.last.frame.image.shape[:2] == tuple(reversed(core.source.get_frame_size()))
        assert core.worker.state().pid == pid
        assert core.worker.last.outcome.vector == (0.6, 0.0, 2.0)  # still in "fly" mode
        assert core.controller is controller and controller.heartbeat_age_s() < core.config.safety.link_timeout
        assert core.telemetry.snapshot().in_air and core.truth.latest()["mode"] == "HOLD"


async def test_a_source_that_fails_to_open_leaves_the_old_one_running(tmp_path: Path) -> None:
    async with flying_core(tmp_path) as core:
        old = core.source
        with pytest.raises(SourceError, match="no such video file"):
            await core.execute(f"source file:{tmp_path / 'missing.mp4'}")
        assert core.source is old
        processed = core.worker.stats.frames_processed
        await wait_until(lambda: core.worker.stats.frames_processed > processed, 30, "frames from the old source")


@pytest.mark.parametrize(("uri", "kind"), [("sim:?width=320", CameraKind.SIM), (" SIM:", CameraKind.SIM),
                                           ("run:runs/2026-01-01", CameraKind.RUN), ("file:sim.mp4", CameraKind.PLAIN),
                                           ("rtsp://run:secret@cam/sim", CameraKind.PLAIN)])
def test_a_cameras_kind_is_read_from_its_uris_scheme(uri: str, kind: CameraKind) -> None:
    assert CameraKind.of(uri) is kind
