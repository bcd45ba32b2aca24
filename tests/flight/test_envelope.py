"""The envelope's limits without a vehicle: its configuration, its shapes, and what it makes of a vector."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from controllers.base import Telemetry
from controllers.sim.geo import Home
from uav_tui.config import EnvelopeConfig, load_config
from uav_tui.errors import ConfigError
from uav_tui.events import EventLog
from uav_tui.flight.envelope import LINK_FRESH_S, Breach, Envelope, configured_envelope
from uav_tui.flight.envelope_shape import EARTH_RADIUS_M

HOME = Home()


def polygon_file(path: Path, corners: list[tuple[float, float]], *, home: Home = HOME) -> Path:
    """A GeoJSON Polygon through ``corners`` (north, east metres from ``home``)."""
    scale = EARTH_RADIUS_M * math.cos(math.radians(home.lat_deg))
    ring = [[home.lon_deg + math.degrees(e / scale), home.lat_deg + math.degrees(n / EARTH_RADIUS_M)]
            for n, e in corners]
    path.write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {}, "geometry": {"type": "Polygon", "coordinates": [ring + ring[:1]]}}]}))
    return path


def at(north: float, east: float, yaw: float = 0.0, **fields: float) -> Telemetry:
    return Telemetry(north_m=north, east_m=east, yaw_deg=yaw, rel_alt_m=fields.pop("rel_alt_m", 3.0), **fields)


def envelope(**keys: object) -> Envelope:
    return Envelope(EnvelopeConfig(**keys), EventLog())  # type: ignore[arg-type]


@pytest.mark.parametrize(("text", "says"), [
    ("{not json", "is not GeoJSON"),
    (json.dumps({"type": "Point", "coordinates": [8.5, 47.4]}), "holds no GeoJSON Polygon"),
    (json.dumps({"type": "Polygon", "coordinates": [[[8.5, 47.4], [8.6, 47.4], [8.5, 47.4]]]}),
     "2 distinct vertices"),
    (json.dumps({"type": "Polygon", "coordinates": [[[0, 0], [1, 1], [1, 0], [0, 1], [0, 0]]]}), "crosses itself"),
    (json.dumps({"type": "Polygon", "coordinates": [[[0, 0], [2, 0], [2, 2], [0, 0]],
                                                    [[0.5, 0.2], [1, 0.2], [1, 0.5], [0.5, 0.2]]]}), "hole"),
    (json.dumps({"type": "Polygon", "coordinates": [[[0, 0], [200, 0], [2, 2], [0, 0]]]}), "off the earth"),
])
def test_a_polygon_file_that_cannot_bound_a_flight_is_refused_at_start(tmp_path: Path, text: str,
                                                                         says: str) -> None:
    (tmp_path / "field.geojson").write_text(text)
    with pytest.raises(ConfigError, match=says) as error:
        load_config(None, {"polygon": str(tmp_path / "field.geojson")})
    assert error.value.key == "--polygon"


def test_a_missing_polygon_file_a_band_upside_down_and_an_unknown_action_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read the polygon file"):
        load_config(None, {"polygon": str(tmp_path / "nowhere.geojson")})
    with pytest.raises(ConfigError, match="min_height_m = 30 is not below max_height_m = 20"):
        load_config(None, {"min_height_m": 30.0, "max_height_m": 20.0})
    with pytest.raises(ConfigError, match="min_home_height_m = 150 is not below max_home_height_m = 120"):
        load_config(None, {"min_home_height_m": 150.0})
    with pytest.raises(ConfigError, match="must be one of hold, rtl, land"):
        load_config(None, {"battery_action": "loiter"})


def test_a_polygon_without_home_stops_a_start_with_the_simulator(tmp_path: Path) -> None:
    away = polygon_file(tmp_path / "away.geojson", [(50, 50), (50, 80), (80, 80), (80, 50)])
    config = load_config(None, {"fc": "sim", "polygon": str(away)})
    with pytest.raises(ConfigError, match=r"home \(47.397742,8.545594\) is 71 m outside the polygon"):
        configured_envelope(config, EventLog())


def test_the_limits_in_force_are_said_in_one_line(tmp_path: Path) -> None:
    assert envelope().describe() == "envelope: height <= 120 m above home (hold); battery above 20 % (rtl)"
    field = polygon_file(tmp_path / "field.geojson", [(-10, -10), (-10, 10), (10, 10), (10, -10)])
    assert envelope(radius_m=50.0, polygon=str(field), min_height_m=3.0, max_home_height_m=0.0, max_autonomy_s=90.0,
                    battery_floor_v=14.2, lost_after_s=2.0, lost_action="rtl").describe() == (
        "envelope: radius 50 m; polygon field.geojson; height >= 3 m above the ground (hold); 90 s an engagement "
        "(hold); battery above 20 % or 14.2 V (rtl); target lost 2 s (rtl)")
    assert envelope(battery_floor_pct=0.0, max_home_height_m=0.0).describe() == "envelope: none"


def test_a_polygon_is_placed_when_the_first_position_gives_home(tmp_path: Path) -> None:
    field = polygon_file(tmp_path / "field.geojson", [(-10, -10), (-10, 10), (10, 10), (10, -10)])
    events = EventLog()
    fence = Envelope(EnvelopeConfig(polygon=str(field)), events)
    assert fence.confine((1.0, 0.0, 1.0), at(0, 0)).note == ("refused: home is not known yet, so the polygon cannot "
                                                             "be placed")
    fence.on_telemetry(Telemetry(lat_deg=HOME.lat_deg + math.degrees(5 / EARTH_RADIUS_M), lon_deg=HOME.lon_deg,
                                 north_m=5.0, east_m=0.0))
    assert fence.confine((1.0, 0.0, 1.0), at(0, 0)).vector == (1.0, 0.0, 1.0)
    cut = fence.confine((1.0, 0.0, 2.0), at(8.5, 0))
    assert cut.vector == pytest.approx((1.0, 0.0, 0.9)) and "cut to 0.90 s" in cut.note


def test_a_vector_is_cut_to_end_on_the_radius_then_refused_there() -> None:
    fence = envelope(radius_m=10.0, response_lag_s=0.5)
    assert fence.confine((1.0, 0.0, 2.0), at(5, 0)).vector == (1.0, 0.0, 2.0)
    cut = fence.confine((1.0, 0.0, 2.0), at(8, 0))
    assert cut.vector == pytest.approx((1.0, 0.0, 1.5)) and fence.cut == 1
    east = fence.confine((1.0, 0.0, 2.0), at(0, 9, yaw=90.0))  # heading east: forward is east
    assert east.vector == pytest.approx((1.0, 0.0, 0.5))
    refused = fence.confine((1.0, 0.0, 2.0), at(9.8, 0))
    assert refused.vector is None and refused.note == "refused: at the 10 m radius, the vector points out"
    assert fence.refused == 1
    braking = fence.confine((1.0, 0.0, 2.0), at(9.8, 0, vn_ms=0.8, ve_ms=0.0))  # still coasting out: brake it
    assert braking.vector == pytest.approx((-0.8, 0.0, 0.5)) and "slid along the 10 m radius" in braking.note


def test_outside_only_the_way_back_in_flies() -> None:
    fence = envelope(radius_m=10.0)
    assert fence.confine((1.0, 0.0, 1.0), at(12, 0)).note == ("refused: 2.0 m outside the 10 m radius: only a "
                                                             "vector back in flies")
    assert fence.confine((0.0, 1.0, 1.0), at(12, 0)).vector is None  # along the boundary is not back in
    back = fence.confine((-1.0, 1.0, 1.0), at(12, 0))
    assert back.vector == pytest.approx((-1.0, 0.0, 1.0)) and "flown straight back in" in back.note
    assert fence.confine((1.0, 0.0, 1.0), at(12, 0, yaw=180.0)).vector == pytest.approx((1.0, 0.0, 1.0))


def test_at_an_edge_a_vector_slides_along_it_and_stops_in_the_corner(tmp_path: Path) -> None:
    field = polygon_file(tmp_path / "field.geojson", [(-10, -10), (-10, 10), (10, 10), (10, -10)])
    fence = envelope(polygon=str(field))
    fence.set_home(HOME.lat_deg, HOME.lon_deg)
    slid = fence.confine((1.0, 1.0, 1.0), at(9.8, 0))  # north-east into the north edge
    assert slid.vector == pytest.approx((0.0, 1.0, 1.0), abs=1e-6) and "slid along" in slid.note
    cornered = fence.confine((1.0, 1.0, 1.0), at(9.8, 9.8))
    assert cornered.vector is None and cornered.note == ("refused: at the polygon of field.geojson, nothing of the "
                                                         "vector stays inside")


def test_the_height_band_the_time_and_the_battery_end_autonomy_with_their_action() -> None:
    clock = [0.0]
    fence = Envelope(EnvelopeConfig(min_height_m=2.0, max_height_m=30.0, max_autonomy_s=60.0, battery_floor_v=14.0,
                                    height_action="land"), EventLog(), clock=lambda: clock[0])
    fence.engage()
    assert fence.breach(at(0, 0, rel_alt_m=10.0, battery_pct=50.0)) is None
    low = fence.breach(at(0, 0, rel_alt_m=1.5))
    assert low is not None and (low.action, low.reason) == ("land", "height 1.5 m above the ground (home) is below "
                                                            "the floor 2 m")
    assert fence.confine((1.0, 0.0, 1.0), at(0, 0, rel_alt_m=1.5)).note.startswith("refused: height 1.5 m")
    ranged = fence.breach(at(0, 0, rel_alt_m=10.0, rangefinder_m=40.0, roll_deg=0.0, pitch_deg=0.0))
    assert ranged is not None and "above the ground (rangefinder) is above the ceiling 30 m" in ranged.reason
    assert fence.breach(Telemetry(), strict=True) is not None  # a band it cannot check keeps vectors back
    assert fence.breach(Telemetry()) is None  # but ends nothing
    battery = fence.breach(at(0, 0, battery_pct=19.0))
    assert battery is not None and (battery.action, battery.reason) == ("rtl", "battery 19 % below the floor 20 %")
    assert "13.90 V below the floor 14 V" in str(fence.breach(at(0, 0, battery_v=13.9)))
    clock[0] = 61.0
    late = fence.breach(at(0, 0))
    assert late is not None and (late.action, late.reason) == ("hold", "autonomy ran its longest engagement, 60 s")


def test_a_target_lost_with_last_seen_goes_back_to_its_last_position_or_holds_without_one() -> None:
    clock = [0.0]
    lost = Envelope(EnvelopeConfig(lost_after_s=2.0, lost_action="last_seen"), EventLog(), clock=lambda: clock[0])
    lost.engage()
    lost.saw(True, Telemetry())  # seen where no position was known
    clock[0] = 2.5
    assert lost.breach(at(0, 0)) == Breach("hold", "target lost for 2 s (no position when it was last seen: hold "
                                                   "instead of last_seen)")
    lost.saw(True, at(4.0, -1.0))
    lost.saw(False, at(9.0, 9.0))
    clock[0] = 4.6
    assert lost.breach(at(9, 9)) == Breach("last_seen", "target lost for 2 s (last seen at 4.0 m N, -1.0 m E)",
                                           (4.0, -1.0))
    with pytest.raises(ConfigError, match="must be one of hold, rtl, land, last_seen"):
        load_config(None, {"lost_action": "circle"})


def test_a_link_quality_below_its_floor_for_link_floor_s_ends_autonomy_and_an_unknown_or_stale_one_never() -> None:
    clock = [0.0]
    link = Envelope(EnvelopeConfig(link_floor_pct=40.0, link_floor_s=2.0, battery_floor_pct=0.0), EventLog(),
                    clock=lambda: clock[0])

    def received(pct: float | None, *, at_s: float, age_s: float = 0.0) -> Telemetry:
        clock[0] = at_s
        t = Telemetry(t_mono_ns=int(at_s * 1e9), link_quality_pct=pct, link_quality_t_ns=int((at_s - age_s) * 1e9))
        link.on_telemetry(t)
        return t

    assert link.breach(received(30.0, at_s=1.0)) is None  # below, not yet for 2 s
    assert link.breach(received(30.0, at_s=2.9)) is None
    assert link.breach(received(30.0, at_s=3.0)) == Breach("rtl", "link quality 30 % below the floor 40 % for 2 s")
    assert link.breach(received(60.0, at_s=3.1)) is None  # back above: the time starts again
    assert link.breach(received(30.0, at_s=4.0)) is None
    assert link.breach(received(None, at_s=6.5)) is None  # unknown
    assert link.breach(received(30.0, at_s=7.0)) is None
    assert link.breach(received(30.0, at_s=20.0, age_s=LINK_FRESH_S + 1)) is None  # nothing new for long: unknown
    assert "link quality above 40 % (for 2 s, rtl)" in link.describe()
