"""The ``sim:`` camera's pose feed drops a pose sample that cannot be true (issue 47): the camera keeps drawing from
the last possible pose, never from a vehicle 10,000 km up or at an attitude beyond a turn."""

from __future__ import annotations

import logging
from collections.abc import AsyncIterator

import pytest

from controllers.base import PoseSample
from sources.pose import PoseTrack
from uav_tui.camera.pose_feed import feed

MS = 1_000_000


async def _samples(samples: list[PoseSample]) -> AsyncIterator[PoseSample]:
    for sample in samples:
        yield sample


async def test_an_impossible_pose_sample_is_dropped_and_said_once(caplog: pytest.LogCaptureFixture) -> None:
    track = PoseTrack()
    samples = [PoseSample("position", 0, (1.0, 2.0, -10.0)), PoseSample("attitude", 0, (0.0, 0.0, 90.0)),
               PoseSample("position", 20 * MS, (1.0, 2.0, -1e10)), PoseSample("position", 40 * MS, (1.0, 2.0, -1e10)),
               PoseSample("attitude", 20 * MS, (0.0, 1e6, 90.0))]
    with caplog.at_level(logging.WARNING, logger="uav_tui.camera.pose_feed"):
        await feed(_samples(samples), track)
    pose = track(0)
    assert pose is not None and (pose.pose.d, pose.pose.pitch) == (-10.0, 0.0)
    assert track(40 * MS).pose.d == -10.0  # type: ignore[union-attr]
    assert [r.getMessage() for r in caplog.records] == [
        "sim: camera pose: position sample dropped: down_m -1e+10 is outside [-20000, 20000]",
        "sim: camera pose: attitude sample dropped: pitch_deg 1e+06 is outside [-90, 90]"]
