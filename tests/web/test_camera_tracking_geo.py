"""CAMERA_TRACKING_GEO_STATUS read by an independent MAVLink client: where the tracked car is on the ground."""

from __future__ import annotations

import asyncio
import contextlib
import math
import socket

import pytest
from pymavlink.dialects.v20 import common as mavlink

from tests.core.flight_helpers import flying_core
from tests.web.conftest import free_port
from tests.web.test_camera_tracking import GroundStation
from uav_tui.flight.geolocate import RANGEFINDER_SIGMA_M

ALTITUDE_M = 20.0


async def test_the_ground_station_hears_where_the_car_is(tmp_path) -> None:
    port = free_port(socket.SOCK_DGRAM)
    source = "sim:?fps=15&targets=1&target_speed=0"  # a parked car 6 m north of home
    async with flying_core(tmp_path, altitude=ALTITUDE_M, source=source, camera_mavlink=f"udpin:127.0.0.1:{port}",
                           processor="tests.recording.recorder_processors:RedCar") as core:
        station = GroundStation(port)
        try:
            car_n, car_e, _ = core.source.targets[0].position(0.0)
            home = core.controller.sim.home
            await station.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION)
            info = await station.receive("CAMERA_INFORMATION")
            assert info.flags & mavlink.CAMERA_CAP_FLAGS_HAS_TRACKING_GEO_STATUS
            await station.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_CAMERA_TRACKING_GEO_STATUS)
            ack = await station.receive("COMMAND_ACK", command=mavlink.MAV_CMD_REQUEST_MESSAGE)
            assert ack.result == mavlink.MAV_RESULT_ACCEPTED
            geo = await station.receive("CAMERA_TRACKING_GEO_STATUS")
            vehicle = core.truth.latest()
        finally:
            station.sock.close()
    assert geo.get_srcComponent() == mavlink.MAV_COMP_ID_CAMERA
    assert geo.tracking_status == mavlink.CAMERA_TRACKING_STATUS_FLAGS_ACTIVE
    north, east, down = home.to_local(geo.lat / 1e7, geo.lon / 1e7, geo.alt)
    error = math.hypot(north - car_n, east - car_e)
    assert error <= 1.0 and error <= geo.h_acc, (north, east, geo.h_acc)  # degE7 is ~1 cm: no rounding error
    assert abs(down) < 0.1  # the car stands on the ground at home's altitude
    assert geo.v_acc == pytest.approx(RANGEFINDER_SIGMA_M) and 0.1 < geo.h_acc < 2.0  # the simulator has one
    slant = math.hypot(car_n - vehicle["n"], car_e - vehicle["e"], vehicle["d"])
    assert geo.dist == pytest.approx(slant, abs=0.5)
    # parked: a velocity near zero from its positions on the frame clock, and no heading; the ground is flat: no vel_d
    assert math.hypot(geo.vel_n, geo.vel_e) < 0.2 and 0 <= geo.vel_acc < 0.2, (geo.vel_n, geo.vel_e, geo.vel_acc)
    assert all(math.isnan(v) for v in (geo.vel_d, geo.hdg, geo.hdg_acc))


async def test_the_ground_station_hears_how_fast_and_which_way_the_car_drives(tmp_path) -> None:
    port = free_port(socket.SOCK_DGRAM)
    speed = 1.5
    source = f"sim:?fps=15&targets=1&target_speed={speed}"  # a car driving round home on a 6 m ring
    heard = []
    async with flying_core(tmp_path, altitude=ALTITUDE_M, source=source, camera_mavlink=f"udpin:127.0.0.1:{port}",
                           processor="tests.recording.recorder_processors:RedCar") as core:
        station = GroundStation(port)
        try:
            await asyncio.sleep(2.5)  # a window of positions
            for _ in range(3):
                with contextlib.suppress(BlockingIOError):  # what was sent before: not news
                    while station.sock.recv(4096):
                        pass
                await station.command(mavlink.MAV_CMD_REQUEST_MESSAGE,
                                      mavlink.MAVLINK_MSG_ID_CAMERA_TRACKING_GEO_STATUS)
                geo = await station.receive("CAMERA_TRACKING_GEO_STATUS")
                car = core.source.get_properties()["targets"][0]
                heard.append((geo, math.atan2(car["e"], car["n"]) + math.pi / 2))  # the ring's tangent, as it drives
                await asyncio.sleep(0.5)
        finally:
            station.sock.close()
    for geo, heading in heard:
        assert geo.tracking_status == mavlink.CAMERA_TRACKING_STATUS_FLAGS_ACTIVE
        assert math.hypot(geo.vel_n, geo.vel_e) == pytest.approx(speed, abs=0.2), (geo.vel_n, geo.vel_e)
        assert 0 < geo.vel_acc < 0.3 and math.isnan(geo.vel_d)
        assert geo.hdg == pytest.approx(math.atan2(geo.vel_e, geo.vel_n) % math.tau, abs=1e-5)
        # the mean heading of the last 2 s: behind the car's by the quarter-radian it turns a second, ~14 deg
        behind = math.degrees((heading - geo.hdg + math.pi) % math.tau - math.pi)
        assert -8.0 <= behind <= 30.0, behind
        assert 0 < geo.hdg_acc < math.radians(15)
