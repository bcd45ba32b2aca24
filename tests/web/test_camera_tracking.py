"""Ground-station click-to-track: MAVLink camera track commands sent with pymavlink -> catch_cmd."""

from __future__ import annotations

import asyncio
import math
import socket
from collections.abc import AsyncIterator
from typing import Any

import pytest
from pymavlink.dialects.v20 import common as mavlink

from tests.web.conftest import free_port, make_core, processor_of
from uav_tui.core import UavCore
from uav_tui.errors import ConfigError
from uav_tui.web.mavlink_tracking import parse_endpoint


class GroundStation:
    """A minimal MAVLink 2 ground station on a non-blocking UDP socket (system 255)."""

    def __init__(self, port: int) -> None:
        self.address = ("127.0.0.1", port)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.setblocking(False)
        self.sock.bind(("127.0.0.1", 0))
        self.mav = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)

    async def command(self, command: int, *params: float, target: tuple[int, int] = (1, 100)) -> None:
        params = (*params, *[0.0] * (7 - len(params)))
        message = self.mav.command_long_encode(*target, command, 0, *params)
        await asyncio.get_running_loop().sock_sendto(self.sock, message.pack(self.mav), self.address)

    async def receive(self, kind: str, timeout: float = 5.0, **match: Any) -> Any:
        loop = asyncio.get_running_loop()
        async with asyncio.timeout(timeout):
            while True:
                data, _ = await loop.sock_recvfrom(self.sock, 4096)
                for message in self.mav.parse_buffer(data) or []:
                    if message.get_type() == kind and all(getattr(message, k) == v for k, v in match.items()):
                        return message


@pytest.fixture
async def tracking() -> AsyncIterator[tuple[UavCore, GroundStation]]:
    port = free_port(socket.SOCK_DGRAM)
    core = make_core(web=False, camera_mavlink=f"udpin:127.0.0.1:{port}")
    await core.start()
    station = GroundStation(port)
    try:
        yield core, station
    finally:
        station.sock.close()
        await core.stop("test finished")


async def test_track_rectangle_and_point_reach_catch_cmd(tracking: tuple[UavCore, GroundStation]) -> None:
    core, station = tracking
    processor = processor_of(core)
    await station.command(mavlink.MAV_CMD_CAMERA_TRACK_RECTANGLE, 0.25, 0.3, 0.55, 0.7)
    ack = await station.receive("COMMAND_ACK", command=mavlink.MAV_CMD_CAMERA_TRACK_RECTANGLE)
    assert ack.result == mavlink.MAV_RESULT_ACCEPTED and ack.target_system == 255
    assert processor.rois == [(160, 144, 192, 192)]
    # the status reports what the processor tracks (its box: the ROI moved by 10 px), not the selection
    status = await station.receive("CAMERA_TRACKING_IMAGE_STATUS",
                                   tracking_status=mavlink.CAMERA_TRACKING_STATUS_FLAGS_ACTIVE)
    assert status.tracking_mode == mavlink.CAMERA_TRACKING_MODE_RECTANGLE
    assert (status.rec_top_x, status.rec_top_y, status.rec_bottom_x, status.rec_bottom_y) == pytest.approx(
        (170 / 640, 154 / 480, 362 / 640, 346 / 480), abs=1e-4)
    assert (status.point_x, status.point_y) == pytest.approx((266 / 640, 250 / 480), abs=1e-4)

    await station.command(mavlink.MAV_CMD_CAMERA_TRACK_POINT, 0.5, 0.5, 0.05)
    ack = await station.receive("COMMAND_ACK", command=mavlink.MAV_CMD_CAMERA_TRACK_POINT)
    assert ack.result == mavlink.MAV_RESULT_ACCEPTED
    assert processor.rois[-1] == (288, 208, 64, 64)
    origins = {e.origin for e in core.events.recent if e.kind == "command" and e.message.startswith("roi")}
    assert origins == {"mavlink:255/190"}

    await station.command(mavlink.MAV_CMD_CAMERA_STOP_TRACKING)
    ack = await station.receive("COMMAND_ACK", command=mavlink.MAV_CMD_CAMERA_STOP_TRACKING)
    assert ack.result == mavlink.MAV_RESULT_ACCEPTED
    await station.receive("CAMERA_TRACKING_IMAGE_STATUS", tracking_status=mavlink.CAMERA_TRACKING_STATUS_FLAGS_IDLE)


async def test_a_box_without_a_ground_position_is_tracked_but_not_located(
        tracking: tuple[UavCore, GroundStation]) -> None:
    core, station = tracking  # no vehicle: no GPS position
    await station.command(mavlink.MAV_CMD_CAMERA_TRACK_RECTANGLE, 0.25, 0.3, 0.55, 0.7)
    await station.receive("CAMERA_TRACKING_IMAGE_STATUS", tracking_status=mavlink.CAMERA_TRACKING_STATUS_FLAGS_ACTIVE)
    geo = await station.receive("CAMERA_TRACKING_GEO_STATUS")
    assert geo.tracking_status == mavlink.CAMERA_TRACKING_STATUS_FLAGS_IDLE and (geo.lat, geo.lon) == (0, 0)
    assert all(math.isnan(v) for v in (geo.alt, geo.h_acc, geo.v_acc, geo.dist))
    assert core.status().target is not None and core.status().target.status != "ok"


async def test_bad_and_unknown_commands_are_refused(tracking: tuple[UavCore, GroundStation]) -> None:
    core, station = tracking
    await station.command(mavlink.MAV_CMD_CAMERA_TRACK_RECTANGLE, 0.2, 0.2, 1.5, 0.4)
    ack = await station.receive("COMMAND_ACK", command=mavlink.MAV_CMD_CAMERA_TRACK_RECTANGLE)
    assert ack.result == mavlink.MAV_RESULT_DENIED
    await station.command(mavlink.MAV_CMD_DO_SET_MODE, 1, 4)
    ack = await station.receive("COMMAND_ACK", command=mavlink.MAV_CMD_DO_SET_MODE)
    assert ack.result == mavlink.MAV_RESULT_UNSUPPORTED
    # addressed to another component: not ours to answer or execute
    await station.command(mavlink.MAV_CMD_CAMERA_TRACK_POINT, 0.5, 0.5, 0, target=(1, 1))
    with pytest.raises(TimeoutError):
        await station.receive("COMMAND_ACK", timeout=0.5, command=mavlink.MAV_CMD_CAMERA_TRACK_POINT)
    assert processor_of(core).rois == []
    assert any("rejected" in e.message for e in core.events.recent if e.level == "warning")


async def test_announces_itself_as_a_tracking_camera(tracking: tuple[UavCore, GroundStation]) -> None:
    _, station = tracking
    await station.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION)
    info = await station.receive("CAMERA_INFORMATION")
    assert info.flags & mavlink.CAMERA_CAP_FLAGS_HAS_TRACKING_POINT
    assert info.flags & mavlink.CAMERA_CAP_FLAGS_HAS_TRACKING_RECTANGLE
    assert (info.resolution_h, info.resolution_v) == (640, 480)
    heartbeat = await station.receive("HEARTBEAT")
    assert heartbeat.type == mavlink.MAV_TYPE_CAMERA and heartbeat.get_srcComponent() == mavlink.MAV_COMP_ID_CAMERA


async def test_a_handler_bug_fails_its_command_is_logged_once_and_the_component_goes_on(
        tracking: tuple[UavCore, GroundStation], monkeypatch: pytest.MonkeyPatch,
        caplog: pytest.LogCaptureFixture) -> None:
    core, station = tracking

    def bug(*args: Any, **kwargs: Any) -> None:
        raise RuntimeError("a bug in the handler")

    monkeypatch.setattr("uav_tui.web.mavlink_tracking.point_to_roi", bug)
    for _ in range(6):
        await station.command(mavlink.MAV_CMD_CAMERA_TRACK_POINT, 0.5, 0.5, 0.05)
        ack = await station.receive("COMMAND_ACK", command=mavlink.MAV_CMD_CAMERA_TRACK_POINT)
        assert ack.result == mavlink.MAV_RESULT_FAILED
    monkeypatch.undo()
    await station.command(mavlink.MAV_CMD_CAMERA_TRACK_POINT, 0.5, 0.5, 0.05)
    ack = await station.receive("COMMAND_ACK", command=mavlink.MAV_CMD_CAMERA_TRACK_POINT)
    assert ack.result == mavlink.MAV_RESULT_ACCEPTED and processor_of(core).rois == [(288, 208, 64, 64)]
    tracebacks = [r for r in caplog.records if r.exc_info and "a bug in the handler" in str(r.exc_info[1])]
    assert len(tracebacks) == 1  # once per kind of failure
    said = [e.message for e in core.events.recent if "a bug in the handler" in e.message]
    assert len(said) == 3 and "RuntimeError" in said[0]  # the rest are counted, within the line budget
    core.camera_tracking.failures.close()
    assert any("3 more handler failures (6 in all)" in e.message for e in core.events.recent)


@pytest.mark.parametrize("address", ["serial:/dev/ttyS0", "udpin:14580", "udpin:0.0.0.0:port", "tcp:host:5760"])
def test_bad_endpoints_say_what_is_expected(address: str) -> None:
    with pytest.raises(ConfigError, match="udpin:HOST:PORT"):
        parse_endpoint(address)


class RaisesAfterSelection:
    """Tracks the ROI, then raises on every frame once F1 is pressed (a processor in trouble)."""

    def __init__(self) -> None:
        self.tmMgr = None
        self.box: tuple[int, int, int, int] | None = None
        self.failing = False

    def photo_processing(self, frame: Any) -> None:
        if self.failing:
            raise RuntimeError("tracker crashed")

    def catch_cmd(self, roi: tuple[int, int, int, int]) -> None:
        self.box = roi

    def customize_processing(self, id: int) -> None:  # noqa: A002 - the published name
        self.failing = True


async def test_a_failing_processor_is_reported_as_a_tracking_error() -> None:
    port = free_port(socket.SOCK_DGRAM)
    core = make_core(web=False, camera_mavlink=f"udpin:127.0.0.1:{port}",
                     processor="tests.web.test_camera_tracking:RaisesAfterSelection")
    await core.start()
    station = GroundStation(port)
    try:
        await station.command(mavlink.MAV_CMD_CAMERA_TRACK_POINT, 0.5, 0.5, 0.05)
        await station.receive("CAMERA_TRACKING_IMAGE_STATUS", tracking_mode=mavlink.CAMERA_TRACKING_MODE_POINT,
                              tracking_status=mavlink.CAMERA_TRACKING_STATUS_FLAGS_ACTIVE)
        await core.execute("f 1")
        status = await station.receive("CAMERA_TRACKING_IMAGE_STATUS",
                                       tracking_status=mavlink.CAMERA_TRACKING_STATUS_FLAGS_ERROR)
        assert status.tracking_mode == mavlink.CAMERA_TRACKING_MODE_NONE
        geo = await station.receive("CAMERA_TRACKING_GEO_STATUS")
        assert geo.tracking_status == mavlink.CAMERA_TRACKING_STATUS_FLAGS_ERROR
    finally:
        station.sock.close()
        await core.stop("test finished")


async def test_udpout_answers_and_a_failed_ack_costs_that_ack_alone(monkeypatch: pytest.MonkeyPatch,
                                                                    caplog: pytest.LogCaptureFixture) -> None:
    station = GroundStation(0)  # the ground station listens; the component sends to it by name
    core = make_core(web=False, camera_mavlink=f"udpout:localhost:{station.sock.getsockname()[1]}")
    await core.start()
    try:
        loop = asyncio.get_running_loop()
        async with asyncio.timeout(5):
            _, station.address = await loop.sock_recvfrom(station.sock, 4096)  # its heartbeat: where it sends from
        await station.command(mavlink.MAV_CMD_CAMERA_TRACK_POINT, 0.5, 0.5, 0.05)
        ack = await station.receive("COMMAND_ACK", command=mavlink.MAV_CMD_CAMERA_TRACK_POINT)
        assert ack.result == mavlink.MAV_RESULT_ACCEPTED

        transport = core.camera_tracking.transport
        send = transport.sendto

        def failing_ack(data: bytes, addr: Any = None) -> None:  # the next COMMAND_ACK meets a broken link
            if int.from_bytes(data[7:10], "little") == mavlink.MAVLINK_MSG_ID_COMMAND_ACK:
                monkeypatch.setattr(transport, "sendto", send)
                raise OSError("the link broke")
            send(data, addr)

        monkeypatch.setattr(transport, "sendto", failing_ack)
        await station.command(mavlink.MAV_CMD_CAMERA_STOP_TRACKING)
        with pytest.raises(TimeoutError):
            await station.receive("COMMAND_ACK", timeout=1.0, command=mavlink.MAV_CMD_CAMERA_STOP_TRACKING)
        await station.command(mavlink.MAV_CMD_CAMERA_TRACK_POINT, 0.5, 0.5, 0.05)
        ack = await station.receive("COMMAND_ACK", command=mavlink.MAV_CMD_CAMERA_TRACK_POINT)
        assert ack.result == mavlink.MAV_RESULT_ACCEPTED
        assert [str(r.exc_info[1]) for r in caplog.records if r.exc_info] == ["the link broke"]
    finally:
        station.sock.close()
        await core.stop("test finished")
