"""CAMERA_TRACKING_GEO_STATUS read by an independent MAVLink client: where the tracked car is on the ground."""

from __future__ import annotations

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
    assert all(math.isnan(v) for v in (geo.vel_n, geo.vel_e, geo.vel_d, geo.vel_acc, geo.hdg, geo.hdg_acc))
