"""Connecting MavsdkController: every bad address or dead link is refused at once with what to check; the paper's
UDP forms still listen; ``sim`` starts its own vehicle and ``none`` means none."""

from __future__ import annotations

import asyncio
import socket
import time

import pytest

from controllers import FlightController, connect_controller
from controllers.mavsdk.controller import MavsdkController
from controllers.sim.launcher import SimVehicle, free_udp_port
from controllers.sim_controller import SimController
from uav_tui.errors import ConnectError

pytestmark = pytest.mark.asyncio(loop_scope="module")


async def test_dead_port_gives_no_heartbeat_within_bounded_time() -> None:
    fc = MavsdkController()
    started = time.monotonic()
    with pytest.raises(ConnectError, match=r"no heartbeat on udpin://0\.0\.0\.0:\d+ within 1 s: check wiring"):
        await fc.connect(f"udpin://0.0.0.0:{free_udp_port()}", heartbeat_timeout=1.0)
    assert time.monotonic() - started < 4.0
    await fc.close()


async def test_port_in_use_is_reported() -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("0.0.0.0", 0))
        port = taken.getsockname()[1]
        with pytest.raises(ConnectError, match="the port is in use"):
            await connect_controller(f"udpin://0.0.0.0:{port}", heartbeat_timeout=1.0)


async def test_nothing_serving_tcp_is_reported() -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]  # bound, not listening: connections are refused
        with pytest.raises(ConnectError, match=f"nothing accepts TCP connections on 127.0.0.1:{port}"):
            await connect_controller(f"tcp://127.0.0.1:{port}", heartbeat_timeout=1.0)


@pytest.mark.parametrize(
    ("address", "says"),
    [
        pytest.param("http://1.2.3.4:80", "unknown connection scheme", id="scheme"),
        pytest.param("udpin://0.0.0.0:70000", "bad port", id="port"),
        pytest.param("serial:///dev/ttyNOPE9:57600", "no serial device /dev/ttyNOPE9", id="serial"),
        pytest.param("sim:", r"did you mean 'sim' \(without the colon\)", id="sim-with-colon"),
        pytest.param("none:", r"did you mean 'none'", id="none-with-colon"),
    ],
)
async def test_bad_connection_strings_fail_at_once(address: str, says: str) -> None:
    started = time.monotonic()
    with pytest.raises(ConnectError, match=says):
        await connect_controller(address)
    assert time.monotonic() - started < 5.0  # refused before waiting the 10 s for a heartbeat


@pytest.mark.parametrize("form", ["udp://:{port}", "udp://127.0.0.1:{port}"], ids=["udp-empty-host", "udp-host"])
async def test_the_papers_udp_forms_listen_like_they_used_to(sim_vehicle: SimVehicle, form: str) -> None:
    fc = await connect_controller(form.format(port=sim_vehicle.mavlink_port), heartbeat_timeout=5.0)
    assert isinstance(fc, MavsdkController)
    try:
        assert fc.connection is not None and fc.connection.scheme == "udpin"
        assert fc.heartbeat_age_s() < 1.5
    finally:
        await fc.close()


async def test_implements_the_flight_controller_contract() -> None:
    assert isinstance(MavsdkController(), FlightController)


async def test_none_means_no_vehicle() -> None:
    assert await connect_controller("none") is None


async def test_sim_starts_its_own_vehicle_and_stops_it_on_close() -> None:
    fc = await connect_controller("sim")
    assert isinstance(fc, SimController)
    try:
        assert fc.sim.running
        assert fc.description.startswith("simulated vehicle (PX4 via udpin://127.0.0.1:")
        truth = fc.sim.truth()  # the platform reaches ground truth this way
        states = [await asyncio.to_thread(truth.wait_latest, 2.0) for _ in range(2)]
        assert any("n" in state for state in states)
        await fc.arm()  # ready at once: the factory waited for the GPS fix
        await fc.disarm()
    finally:
        await fc.close()
    assert not fc.sim.running
