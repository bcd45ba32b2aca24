"""Where the height above the ground comes from: the readings, their age, and the autopilot messages they come in."""

from __future__ import annotations

import json
import math
from types import SimpleNamespace

import pytest

from controllers.base import Telemetry
from controllers.mavsdk.terrain import from_altitude, from_terrain_report
from uav_tui.flight import geolocate
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.recording.interpolate import TelemetryHistory
from uav_values.camera import CameraModel

S = 1_000_000_000
LEVEL = {"roll_deg": 0.0, "pitch_deg": 0.0, "rel_alt_m": 23.0}


def test_altitude_gives_the_clearance_not_px4s_terrain_altitude() -> None:
    def altitude(terrain: float, clearance: float) -> SimpleNamespace:
        return SimpleNamespace(altitude_terrain_m=terrain, bottom_clearance_m=clearance)

    # PX4 SIH at 20 m: altitude_terrain is the ground's local altitude (~0.7 m there), bottom_clearance the height
    assert from_altitude(altitude(0.7, 19.3)) == {"terrain_height_m": 19.3}
    assert from_altitude(altitude(0.7, math.nan)) == {"terrain_height_m": None}  # no distance to the ground
    assert from_altitude(altitude(-1e4, -1.0)) == {"terrain_height_m": None}  # negative: unmeasured


def test_terrain_report_gives_the_current_height_only_with_terrain_data() -> None:
    def report(**fields: object) -> SimpleNamespace:
        return SimpleNamespace(fields_json=json.dumps(fields), system_id=1)

    assert from_terrain_report(report(spacing=100, current_height=31.5, terrain_height=488.0)) == \
        {"terrain_height_m": 31.5}
    assert from_terrain_report(report(spacing=0, current_height=0.0)) == {"terrain_height_m": None}
    assert from_terrain_report(SimpleNamespace(fields_json="{not json", system_id=1)) == {}


def test_the_best_reading_young_enough_is_used_and_why_not_the_others_is_said() -> None:
    at = 100 * S
    both = {**LEVEL, "rangefinder_m": 20.0, "rangefinder_t_ns": at - S // 10, "terrain_height_m": 21.0,
            "terrain_t_ns": at - S // 10}
    assert geolocate.ground_height(both, at) == (20.0, geolocate.FROM_RANGEFINDER, "")
    old_range = {**both, "rangefinder_t_ns": at - int(1.3 * S)}
    assert geolocate.ground_height(old_range, at) == (21.0, geolocate.FROM_TERRAIN, "rangefinder 1.3 s old")
    both_old = {**old_range, "terrain_t_ns": at - int(0.6 * S)}
    assert geolocate.ground_height(both_old, at) == (23.0, geolocate.FROM_HOME,
                                                     "rangefinder 1.3 s old; terrain 0.6 s old")
    at_bound = {**both_old, "terrain_t_ns": at - int(geolocate.READING_MAX_AGE_S * S)}
    assert geolocate.ground_height(at_bound, at)[1] == geolocate.FROM_TERRAIN
    # no capture time, or no receive time (a run recorded before they were): the reading is not judged
    assert geolocate.ground_height(both_old, None)[1] == geolocate.FROM_RANGEFINDER
    assert geolocate.ground_height({**LEVEL, "terrain_height_m": 21.0}, at)[1] == geolocate.FROM_TERRAIN
    # out of range (None) is no reading at all, not a stale one
    assert geolocate.ground_height({**both_old, "rangefinder_m": None, "terrain_height_m": None}, at) == \
        (23.0, geolocate.FROM_HOME, "")


def test_the_terrain_height_locates_with_its_own_uncertainty_and_says_so() -> None:
    camera = CameraModel.from_hfov(640, 480, 62.0)
    pose = {**LEVEL, "yaw_deg": 0.0, "lat_deg": 47.0, "lon_deg": 8.0, "terrain_height_m": 20.0, "terrain_t_ns": 0}
    fix = geolocate.locate_row(camera, (400, 300, 20, 20), {**pose, "rangefinder_m": 19.0, "rangefinder_t_ns": -S},
                               at_ns=S // 10)
    assert (fix.height_m, fix.height_from, fix.height_note) == (20.0, geolocate.FROM_TERRAIN, "rangefinder 1.1 s old")
    home = geolocate.locate_row(camera, (400, 300, 20, 20), {**pose, "terrain_height_m": None})
    assert fix.uncertainty_m > home.uncertainty_m  # 2 m of height error assumed, not 0.5 m
    assert "(height from terrain: rangefinder 1.1 s old)" in geolocate.describe(fix)


def test_the_platform_stamps_each_reading_and_a_replay_keeps_the_recorded_stamp() -> None:
    manager = TelemetryManager(None)
    first = manager.apply({"rangefinder_m": 12.0, "t_mono_ns": 5 * S})
    later = manager.apply({"roll_deg": 1.0, "t_mono_ns": 6 * S})  # no reading: its stamp stays
    assert (first.rangefinder_t_ns, later.rangefinder_t_ns, later.terrain_t_ns) == (5 * S, 5 * S, None)
    replayed = manager.apply({"rangefinder_m": 12.0, "rangefinder_t_ns": 3 * S, "t_mono_ns": 7 * S})
    assert replayed.rangefinder_t_ns == 3 * S
    # A frame's row takes the stamp from the newest sample at or before its capture: the age of what it holds.
    history = TelemetryHistory()
    history.add(first, 5 * S)
    history.add(later, 6 * S)
    history.add(Telemetry(rangefinder_m=13.0, rangefinder_t_ns=7 * S), 7 * S)
    values, _ = history.at(int(6.5 * S))
    # 12 from 5 to 6 (unchanged for 1 s while telemetry came: constant until then), 13 at 7
    assert values["rangefinder_t_ns"] == 5 * S and values["rangefinder_m"] == pytest.approx(12.5)
