"""``--fc sim`` stays on loopback: the platform's MAVLink socket and the simulator's own sockets bind to
127.0.0.1, so nothing on the drone's network can forge the vehicle's state; on loopback, another system
id's HEARTBEAT does not change what is shown."""

from __future__ import annotations

import asyncio
import os
import socket
from pathlib import Path

from controllers import connect_controller
from controllers.sim import px4_modes
from controllers.sim.guidance import Mode
from controllers.sim.link import mavlink
from tests.core.flight_helpers import wait_until
from uav_tui.flight.telemetry import TelemetryManager

LOOPBACK_HEX = "0100007F"
"""127.0.0.1 as /proc/net/udp writes it."""


def udp_bindings(port: int) -> set[str]:
    """Local addresses (hex, /proc/net/udp format) of this machine's UDP sockets bound to ``port``."""
    found = set()
    for line in Path("/proc/net/udp").read_text().splitlines()[1:]:
        address, hex_port = line.split()[1].split(":")
        if int(hex_port, 16) == port:
            found.add(address)
    return found


async def test_platform_and_simulator_sockets_bind_to_loopback_only() -> None:
    fc = await connect_controller("sim", heartbeat_timeout=10.0)
    try:
        sim = fc.sim
        assert fc.connection.url == f"udpin://127.0.0.1:{sim.mavlink_port}"
        assert udp_bindings(sim.mavlink_port) == {LOOPBACK_HEX}  # the platform's MAVSDK socket
        assert udp_bindings(sim.truth_port) == {LOOPBACK_HEX}  # the simulator's ground-truth channel
    finally:
        await fc.close()


async def test_forged_heartbeat_from_another_system_changes_nothing_shown() -> None:
    fc = await connect_controller("sim", heartbeat_timeout=10.0)
    telemetry = TelemetryManager(fc)
    pump = asyncio.create_task(telemetry.run())
    forger = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        await wait_until(lambda: telemetry.snapshot().flight_mode is not None, 10, "telemetry")
        os.environ.setdefault("MAVLINK20", "1")
        encoder = mavlink.MAVLink(None, srcSystem=42, srcComponent=1)
        land_armed = encoder.heartbeat_encode(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_PX4,
                                              px4_modes.base_mode(Mode.LAND, True), px4_modes.custom_mode(Mode.LAND),
                                              mavlink.MAV_STATE_ACTIVE)
        in_air = encoder.extended_sys_state_encode(0, mavlink.MAV_LANDED_STATE_IN_AIR)
        shown = set()
        for _ in range(40):  # 2 s: the simulator's own heartbeats come at 1 Hz
            for msg in (land_armed, in_air):
                forger.sendto(msg.pack(encoder), ("127.0.0.1", fc.sim.mavlink_port))
            await asyncio.sleep(0.05)
            t = telemetry.snapshot()
            shown.add((t.flight_mode, t.armed, t.in_air))
        assert shown == {("HOLD", False, False)}  # with srcSystem=1 it shows ("LAND", True, True)
        assert fc.sim.truth(subscribe=False).request({"cmd": "state"})["state"]["armed"] is False
    finally:
        forger.close()
        pump.cancel()
        await asyncio.gather(pump, return_exceptions=True)
        await fc.close()
