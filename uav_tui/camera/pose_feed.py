"""The ``sim:`` camera's pose, fed from the flight controller's telemetry (any MAVLink autopilot)."""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import AsyncIterator

from controllers.base import PoseSample
from sources.pose import PoseTrack
from uav_tui.flight.telemetry_sanity import pose_problem

logger = logging.getLogger(__name__)

FIRST_POSE_TIMEOUT_S = 5.0
"""How long opening a ``sim:`` camera waits for the vehicle's first pose before drawing the default hover."""


async def feed(samples: AsyncIterator[PoseSample], track: PoseTrack) -> None:
    """Copy ``controller.pose_samples()`` into ``track`` until the controller closes; a sample that cannot be true
    (:func:`~uav_tui.flight.telemetry_sanity.pose_problem`) is dropped, each kind said once."""
    said: set[str] = set()
    async for sample in samples:
        if why := pose_problem(sample.kind, sample.values):
            if sample.kind not in said:
                said.add(sample.kind)
                logger.warning("sim: camera pose: %s sample dropped: %s", sample.kind, why)
        elif sample.kind == "position":
            track.add_position(sample.t_mono_ns, *sample.values)
        elif sample.kind == "attitude":
            track.add_attitude(sample.t_mono_ns, *sample.values)
        else:
            track.add_gimbal(sample.t_mono_ns, *sample.values, earth=sample.kind == "gimbal_earth")


async def wait_first_pose(track: PoseTrack, timeout_s: float = FIRST_POSE_TIMEOUT_S) -> bool:
    """True once ``track`` knows a pose; False after ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    while track(time.monotonic_ns()) is None:
        if time.monotonic() > deadline:
            return False
        await asyncio.sleep(0.02)
    return True
