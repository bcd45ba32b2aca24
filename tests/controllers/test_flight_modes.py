"""Flight-mode names from HEARTBEAT: MAVSDK's where it has one, the autopilot's own where MAVSDK says UNKNOWN, and
a distinct spelled-out name for any other number."""

from __future__ import annotations

import pytest
from pymavlink import mavutil

from controllers.flight_modes import MAVSDK_NAMES, decode

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
