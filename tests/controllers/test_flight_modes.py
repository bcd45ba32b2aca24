"""Flight-mode names from HEARTBEAT: MAVSDK's where it has one, the autopilot's own where MAVSDK says UNKNOWN, and
a distinct spelled-out name for any other number; and the link monitor that chooses between MAVSDK and the
HEARTBEAT."""

from __future__ import annotations

import asyncio
import json
from collections.abc import AsyncGenerator
from typing import Any

import pytest
from mavsdk.asyncio.plugins.mavlink_direct import MavlinkMessage
from mavsdk.asyncio.plugins.telemetry import FlightMode
from pymavlink import mavutil

from controllers.flight_modes import MAVSDK_NAMES, decode
from controllers.mavsdk.calls import Subscriptions
from controllers.mavsdk.link import LinkMonitor

PX4, ARDUPILOT = 12, 3
QUADROTOR, FIXED_WING = 2, 1
CUSTOM = 1 | 16 | 8  # MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, STABILIZE, GUIDED


def px4(main: int, sub: int = 0) -> int:
    """custom_mode of PX4 main mode ``main``, sub mode ``sub`` (px4_custom_mode.h: main in byte 2, sub in byte 3)."""
    return main << 16 | sub << 24


@pytest.mark.parametrize(("main", "sub", "name"), [
    (1, 0, "MANUAL"), (2, 0, "ALTCTL"), (3, 0, "POSCTL"), (3, 1, "POSCTL"), (5, 0, "ACRO"), (6, 0, "OFFBOARD"),
    (7, 0, "STABILIZED"), (8, 0, "RATTITUDE"), (9, 0, "SIMPLE"), (10, 0, "TERMINATION"),
    (4, 1, "READY"), (4, 2, "TAKEOFF"), (4, 3, "HOLD"), (4, 4, "MISSION"), (4, 5, "RETURN_TO_LAUNCH"), (4, 6, "LAND"),
    (4, 8, "FOLLOW_ME"), (4, 9, "PRECISION_LAND"), (4, 10, "VTOL_TAKEOFF"), (4, 11, "EXTERNAL1"), (4, 18, "EXTERNAL8"),
    (4, 7, "PX4_MAIN4_SUB7"), (4, 19, "PX4_MAIN4_SUB19"), (4, 0, "PX4_MAIN4_SUB0"), (11, 2, "PX4_MAIN11_SUB2"),
])
def test_px4_modes_by_main_and_sub_mode(main: int, sub: int, name: str) -> None:
    assert decode(PX4, QUADROTOR, CUSTOM, px4(main, sub)) == name


def test_px4_names_agree_with_pymavlink_layout_and_mavsdk_vocabulary() -> None:
    """pymavlink's table (base_mode, main, sub) of PX4's modes, named the way MAVSDK names them."""
    mavsdk_name = {"LOITER": "HOLD", "RTL": "RETURN_TO_LAUNCH", "FOLLOWME": "FOLLOW_ME", "RTGS": "PX4_MAIN4_SUB7"}
    for pymavlink_name, (base_mode, main, sub) in mavutil.px4_map.items():
        wanted = mavsdk_name.get(pymavlink_name, pymavlink_name)
        assert decode(PX4, QUADROTOR, base_mode, px4(main, sub)) == wanted, pymavlink_name


MAVSDK_COPTER = {0: "STABILIZED", 1: "ACRO", 2: "ALTCTL", 3: "MISSION", 4: "OFFBOARD", 5: "HOLD", 6: "RETURN_TO_LAUNCH",
                 9: "LAND", 16: "POSCTL", 22: "HOLD", 23: "FOLLOW_ME", 27: "RETURN_TO_LAUNCH"}
"""ArduCopter number -> MAVSDK's name (MAVSDK's to_flight_mode_from_ardupilot_copter_mode); every other is
UNKNOWN to MAVSDK."""


def test_arducopter_modes_are_mavsdks_names_or_arducopters_own() -> None:
    removed = {8, 10}  # POSITION, OF_LOITER: gone from ArduCopter, still in pymavlink's table
    for number, ardupilot_name in mavutil.mode_mapping_acm.items():
        wanted = MAVSDK_COPTER.get(number, f"ARDUCOPTER_MODE{number}" if number in removed else ardupilot_name)
        assert decode(ARDUPILOT, QUADROTOR, CUSTOM, number) == wanted, ardupilot_name
    assert decode(ARDUPILOT, QUADROTOR, CUSTOM, 30) == "ARDUCOPTER_MODE30"


def test_every_mode_mavsdk_cannot_name_gets_a_name_of_its_own() -> None:
    modes = [(main, 0) for main in range(12) if main != 4] + [(4, sub) for sub in range(20)]  # sub: AUTO's only
    names = [decode(PX4, QUADROTOR, CUSTOM, px4(main, sub)) for main, sub in modes]
    unnamed = [name for name in names if name not in MAVSDK_NAMES]
    assert len(unnamed) == len(set(unnamed)) and "UNKNOWN" not in unnamed
    copter = [decode(ARDUPILOT, QUADROTOR, CUSTOM, n) for n in range(40) if n not in MAVSDK_COPTER]
    assert len(copter) == len(set(copter)) and not set(copter) & MAVSDK_NAMES


def test_other_vehicles_autopilots_and_flags_are_spelled_out() -> None:
    assert decode(ARDUPILOT, FIXED_WING, CUSTOM, 12) == "ARDUPILOT_TYPE1_MODE12"  # Plane numbers its modes otherwise
    assert decode(ARDUPILOT, 10, CUSTOM, 4) == "ARDUPILOT_TYPE10_MODE4"
    assert decode(PX4, QUADROTOR, 16, px4(4, 9)) == "BASE_MODE16"  # no custom mode: custom_mode means nothing
    assert decode(0, QUADROTOR, CUSTOM, 5) == "AUTOPILOT0_MODE5"


# ---- LinkMonitor: MAVSDK's name, the HEARTBEAT's where MAVSDK says UNKNOWN ------------------------------------------

class Feed:
    """A subscribe_* stream the test pushes items into."""

    def __init__(self) -> None:
        self.queue: asyncio.Queue[Any] = asyncio.Queue()

    async def stream(self) -> AsyncGenerator[Any, None]:
        while True:
            yield await self.queue.get()


class Plugins:
    """MavlinkDirect and Telemetry as LinkMonitor uses them: HEARTBEATs and MAVSDK's flight modes, pushed by hand."""

    def __init__(self) -> None:
        self.heartbeats, self.modes, self.sys_status = Feed(), Feed(), Feed()

    def subscribe_message(self, name: str) -> AsyncGenerator[Any, None]:
        assert name in ("HEARTBEAT", "SYS_STATUS")  # the link reads the radio's presence from SYS_STATUS too
        return (self.heartbeats if name == "HEARTBEAT" else self.sys_status).stream()

    def subscribe_flight_mode(self) -> AsyncGenerator[Any, None]:
        return self.modes.stream()


def heartbeat(custom_mode: int, autopilot: int = PX4) -> MavlinkMessage:
    fields = {"type": QUADROTOR, "autopilot": autopilot, "base_mode": CUSTOM, "custom_mode": custom_mode,
              "system_status": 4, "mavlink_version": 3}
    return MavlinkMessage(message_name="HEARTBEAT", system_id=1, component_id=1, target_system_id=0,
                          target_component_id=0, fields_json=json.dumps(fields))


async def settle() -> None:
    for _ in range(5):
        await asyncio.sleep(0)


async def test_the_mode_is_mavsdks_name_unless_it_says_unknown_then_the_heartbeats() -> None:
    plugins, subscriptions = Plugins(), Subscriptions()
    link = LinkMonitor(plugins, plugins, 1, subscriptions)  # type: ignore[arg-type]
    link.start()
    seen: list[str] = []
    follower = link.follow_modes(lambda update: seen.append(update["flight_mode"]))
    await settle()  # the readers and the follower are in place
    try:
        async def report(custom_mode: int, mavsdk: FlightMode, mavsdk_first: bool) -> str | None:
            if mavsdk_first:
                plugins.modes.queue.put_nowait(mavsdk)
                await settle()
            plugins.heartbeats.queue.put_nowait(heartbeat(custom_mode))
            await settle()
            plugins.modes.queue.put_nowait(mavsdk)
            await settle()
            return link.flight_mode_since(0.0)

        assert await report(px4(4, 3), FlightMode.HOLD, mavsdk_first=False) == "HOLD"
        assert await report(px4(4, 9), FlightMode.UNKNOWN, mavsdk_first=True) == "PRECISION_LAND"
        assert await report(px4(4, 10), FlightMode.UNKNOWN, mavsdk_first=False) == "VTOL_TAKEOFF"  # both UNKNOWN
        assert await report(px4(6), FlightMode.OFFBOARD, mavsdk_first=False) == "OFFBOARD"
        assert await report(px4(4, 9), FlightMode.UNKNOWN, mavsdk_first=False) == "PRECISION_LAND"
        assert await report(px4(3), FlightMode.POSCTL, mavsdk_first=True) == "POSCTL"
        # None before MAVSDK's first report (a late one would look like a switch); HOLD -> PRECISION_LAND with MAVSDK's
        # UNKNOWN first: the old HOLD HEARTBEAT is not taken for the new mode
        assert seen == ["HOLD", "PRECISION_LAND", "PRECISION_LAND", "VTOL_TAKEOFF", "VTOL_TAKEOFF", "OFFBOARD",
                        "OFFBOARD", "PRECISION_LAND", "POSCTL", "POSCTL"]
    finally:
        follower.cancel()
        await subscriptions.close()
