"""A click inside a track's box locks that track: on the web page and from a ground station (CAMERA_TRACK_POINT);
a click elsewhere still selects a region for the processor (issue 50)."""

from __future__ import annotations

import socket
from typing import Any

import aiohttp
import pytest
from pymavlink.dialects.v20 import common as mavlink

from tests.core.flight_helpers import wait_until
from tests.web.conftest import TOKEN, RecordingProcessor, free_port, make_core, processor_of
from tests.web.test_access import base
from tests.web.test_camera_tracking import GroundStation
from uav_tui.flight.track_lock import LockState

CARS = (((100, 100, 80, 40), "car", 0.9), ((400, 300, 60, 60), "car", 0.8))
"""Two parked cars in the 640 x 480 synthetic picture."""


class TwoCars(RecordingProcessor):
    """The page tests' processor, detecting :data:`CARS` on every frame."""

    def __init__(self) -> None:
        super().__init__()
        self.detections = list(CARS)


def track_of(core: Any, box: tuple[int, int, int, int]) -> int:
    return next(d.track_id for d in core.lock.newest if d.box == box)


async def test_a_click_on_the_page_inside_a_track_locks_it_and_elsewhere_selects_a_region() -> None:
    core = make_core(processor="tests.web.test_lock_click:TwoCars")
    await core.start()
    try:
        await wait_until(lambda: len(core.lock.newest) == 2, 10, "both cars tracked")
        second = track_of(core, CARS[1][0])
        async with aiohttp.ClientSession(headers={"Authorization": f"Bearer {TOKEN}"}) as http:
            async with http.post(base(core) + "/api/roi", json={"point": [430 / 640, 330 / 480]}) as response:
                assert response.status == 200
                assert (await response.json())["message"] == f"locked on track #{second} (car)"
            assert core.lock.state is LockState.LOCKED and core.lock.track_id == second
            await wait_until(lambda: core.status().box == CARS[1][0], 5, "the locked car's box as the frame's box")
            assert core.status().lock == f"locked on #{second} car"
            async with http.post(base(core) + "/api/roi", json={"point": [0.5, 0.1]}) as response:  # no car there
                assert response.status == 200
            async with http.post(base(core) + "/api/command", json={"command": "unlock"}) as response:
                assert response.status == 200
        assert processor_of(core).rois == [(296, 24, 48, 48)] and core.lock.state is LockState.OFF
        assert any(e.message == f"lock on #{second} car released: operator" and e.origin.startswith("web:")
                   for e in core.events.recent)
    finally:
        await core.stop("test finished")


async def test_a_ground_stations_track_point_inside_a_track_locks_it_and_stop_tracking_releases_it() -> None:
    port = free_port(socket.SOCK_DGRAM)
    core = make_core(web=False, camera_mavlink=f"udpin:127.0.0.1:{port}", processor="tests.web.test_lock_click:TwoCars")
    await core.start()
    station = GroundStation(port)
    try:
        await wait_until(lambda: len(core.lock.newest) == 2, 10, "both cars tracked")
        first = track_of(core, CARS[0][0])
        await station.command(mavlink.MAV_CMD_CAMERA_TRACK_POINT, 140 / 640, 120 / 480, 0.05)
        ack = await station.receive("COMMAND_ACK", command=mavlink.MAV_CMD_CAMERA_TRACK_POINT)
        assert ack.result == mavlink.MAV_RESULT_ACCEPTED and core.lock.track_id == first
        status = await station.receive("CAMERA_TRACKING_IMAGE_STATUS",
                                       tracking_status=mavlink.CAMERA_TRACKING_STATUS_FLAGS_ACTIVE)
        assert (status.rec_top_x, status.rec_top_y) == pytest.approx((100 / 640, 100 / 480))  # the locked car
        await station.command(mavlink.MAV_CMD_CAMERA_STOP_TRACKING)
        await station.receive("COMMAND_ACK", command=mavlink.MAV_CMD_CAMERA_STOP_TRACKING)
        assert core.lock.state is LockState.OFF and processor_of(core).rois == []
    finally:
        station.sock.close()
        await core.stop("test finished")
