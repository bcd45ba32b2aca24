"""The simulated airframe on its own: kinematics and flight modes, in simulated time (no process)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from controllers.sim.geo import Home
from controllers.sim.guidance import Mode, OffboardSetpoint, Orbit
from controllers.sim.physics import CommandRefused, Multicopter, PhysicsConfig

DT = 0.02


def run(v: Multicopter, seconds: float) -> None:
    for _ in range(round(seconds / DT)):
        v.step(DT)


def hovering(altitude: float = 3.0, **kwargs: object) -> Multicopter:
    v = Multicopter(**kwargs)  # type: ignore[arg-type]
    run(v, v.cfg.gps_fix_after_s + DT)
    v.arm()
    v.takeoff(altitude)
    run(v, altitude / v.cfg.takeoff_speed_ms + 2.0)
    assert v.mode == Mode.HOLD and v.in_air
    return v


def test_arm_refused_before_gps_fix_then_accepted() -> None:
    v = Multicopter()
    with pytest.raises(CommandRefused) as err:
        v.arm()
    assert err.value.temporary
    run(v, v.cfg.gps_fix_after_s + DT)
    v.arm()
    assert v.armed


def test_takeoff_climbs_at_takeoff_speed_to_altitude_then_holds() -> None:
    v = Multicopter()
    run(v, 1.1)
    v.arm()
    v.takeoff(3.0)
    run(v, 1.0)
    assert v.mode == Mode.TAKEOFF and 0.5 < v.altitude < 1.5
    assert -v.vel[2] == pytest.approx(1.5, abs=0.15)
    run(v, 3.0)
    assert v.mode == Mode.HOLD
    assert v.altitude == pytest.approx(3.0, abs=0.15)
    run(v, 2.0)
    assert np.linalg.norm(v.vel) < 0.05
    assert v.altitude == pytest.approx(3.0, abs=0.1)


def test_velocity_response_has_time_constant_and_acceleration_limit() -> None:
    v = hovering()
    v.set_offboard(OffboardSetpoint(velocity=(1.0, 0.0, 0.0)))
    run(v, 0.4)
    # first-order: 1 - e^-1 = 63 % after one time constant
    assert v.vel[0] == pytest.approx(0.63, abs=0.06)
    run(v, 2.0)
    assert v.vel[0] == pytest.approx(1.0, abs=0.02)
    v.set_offboard(OffboardSetpoint(velocity=(10.0, 0.0, 0.0)))
    before = v.vel[0]
    run(v, 0.2)
    assert (v.vel[0] - before) / 0.2 == pytest.approx(3.0, rel=0.05)


def test_attitude_follows_acceleration_in_body_frame() -> None:
    v = hovering()
    v.yaw = math.radians(90.0)
    v.guidance.hold()
    v.set_offboard(OffboardSetpoint(velocity=(0.0, 5.0, 0.0)))
    run(v, 0.3)
    roll, pitch, yaw = v.attitude()
    # accelerating east while facing east: nose down, wings level, tilt ~ atan(3/g)
    assert math.degrees(pitch) == pytest.approx(-math.degrees(math.atan(3.0 / 9.80665)), abs=2.0)
    assert abs(math.degrees(roll)) < 1.0
    assert math.degrees(yaw) == pytest.approx(90.0, abs=0.5)
    v.set_offboard(OffboardSetpoint(velocity=(5.0, 5.0, 0.0)))
    run(v, 0.5)
    roll, _, _ = v.attitude()
    assert math.degrees(roll) < -5.0  # accelerating north = to the left when facing east


def test_body_velocity_is_rotated_by_yaw() -> None:
    v = hovering()
    v.yaw = math.radians(90.0)
    v.guidance.hold()
    start = v.pos.copy()
    v.set_offboard(OffboardSetpoint(velocity=(1.0, 0.0, 0.0), body=True, yaw_rate=0.0))
    run(v, 3.0)
    moved = v.pos - start
    assert moved[1] > 2.0 and abs(moved[0]) < 0.05 and abs(moved[2]) < 0.05
    v.set_offboard(OffboardSetpoint(velocity=(0.0, 1.0, 0.0), body=True, yaw_rate=0.0))
    run(v, 2.0)
    assert v.vel[0] == pytest.approx(-1.0, abs=0.05)  # right of east-facing is south


def test_land_descends_touches_down_and_disarms() -> None:
    v = hovering(2.0)
    v.guidance.land()
    run(v, 1.5)
    assert v.vel[2] == pytest.approx(0.7, abs=0.05)
    run(v, 2.0 / 0.7 + v.cfg.land_disarm_delay_s)
    assert not v.in_air and not v.armed and v.altitude == 0.0
    assert "Takeoff detected" in v.events
    assert v.events[-2:] == ["Landing detected at n=0.0 e=0.0", "Disarmed by landing"]


def test_disarm_in_air_refused_unless_forced() -> None:
    v = hovering(2.0)
    with pytest.raises(CommandRefused):
        v.disarm()
    assert v.armed
    v.disarm(force=True)
    run(v, 1.5)
    assert not v.armed and not v.in_air and v.altitude == 0.0


def test_armed_vehicle_that_never_takes_off_disarms_itself() -> None:
    v = Multicopter(PhysicsConfig(preflight_disarm_s=2.0))
    run(v, 1.1)
    v.arm()
    run(v, 1.5)
    assert v.armed
    run(v, 1.0)
    assert not v.armed


def test_orbit_holds_radius_speed_and_faces_centre() -> None:
    v = hovering(3.0)
    v.guidance.orbit(Orbit(north=0.0, east=0.0, down=-3.0, radius=5.0, speed=2.0))
    run(v, 15.0)
    radii, speeds = [], []
    for _ in range(300):
        v.step(DT)
        radii.append(math.hypot(v.pos[0], v.pos[1]))
        speeds.append(math.hypot(v.vel[0], v.vel[1]))
    assert min(radii) > 4.8 and max(radii) < 5.2
    assert np.mean(speeds) == pytest.approx(2.0, abs=0.1)
    bearing_to_centre = math.atan2(-v.pos[1], -v.pos[0])
    assert abs((v.yaw - bearing_to_centre + math.pi) % (2 * math.pi) - math.pi) < math.radians(10)
    # positive speed is clockwise seen from above: north of the centre moving east
    cross = v.pos[0] * v.vel[1] - v.pos[1] * v.vel[0]
    assert cross > 0


def test_rtl_climbs_returns_home_and_lands() -> None:
    v = hovering(2.0, config=PhysicsConfig(rtl_alt_m=4.0))
    v.pos[:2] = (12.0, -5.0)
    v.guidance.hold()
    v.guidance.rtl()
    max_alt = 0.0
    for _ in range(round(25.0 / DT)):
        v.step(DT)
        max_alt = max(max_alt, v.altitude)
    assert max_alt == pytest.approx(4.0, abs=0.3)
    assert not v.armed and not v.in_air
    assert math.hypot(v.pos[0], v.pos[1]) < 0.3


@pytest.mark.parametrize("wind", [(3.0, 0.0), (0.0, -4.0)], ids=["north3", "west4"])
def test_hold_fights_wind_with_a_small_error(wind: tuple[float, float]) -> None:
    v = hovering(3.0, wind=wind)
    v.guidance.hold()
    target = v.guidance.target.copy()
    run(v, 10.0)
    error = v.pos[:2] - target[:2]
    assert 0.05 < np.linalg.norm(error) < 0.5
    assert np.dot(error, wind) > 0  # pushed downwind
    _, pitch, _ = v.attitude()
    if wind[0] > 0:
        assert math.degrees(pitch) > 1.0  # leaning into a north wind while facing north: nose up


def test_offboard_velocity_in_wind_has_small_steady_error() -> None:
    v = hovering(3.0, wind=(0.0, 3.0))
    v.set_offboard(OffboardSetpoint(velocity=(1.0, 0.0, 0.0)))
    run(v, 5.0)
    assert v.vel[0] == pytest.approx(1.0, abs=0.05)
    assert 0.05 < v.vel[1] < 0.3


def test_same_seed_same_noisy_telemetry() -> None:
    a = Multicopter(PhysicsConfig(noise=True), seed=7)
    b = Multicopter(PhysicsConfig(noise=True), seed=7)
    c = Multicopter(PhysicsConfig(noise=True), seed=8)
    sa, sb, sc = (np.asarray(x.noisy(x.pos, "pos")) for x in (a, b, c))
    assert np.array_equal(sa, sb) and not np.array_equal(sa, sc)
    assert np.array_equal(Multicopter().noisy(np.zeros(3), "pos"), np.zeros(3))


def test_flat_earth_round_trip() -> None:
    home = Home()
    lat, lon, alt = home.to_global(100.0, -50.0, -10.0)
    assert lat > home.lat_deg and lon < home.lon_deg and alt == pytest.approx(498.0)
    assert home.to_local(lat, lon, alt) == pytest.approx((100.0, -50.0, -10.0), abs=1e-6)
    assert Home.parse("1.5, 2.5, 3") == Home(1.5, 2.5, 3.0)
    with pytest.raises(ValueError):
        Home.parse("1,2")


def test_reposition_flies_at_cruise_speed_and_holds_there() -> None:
    v = hovering(2.0)
    v.guidance.goto(30.0, 0.0, -4.0)
    top_speed = 0.0
    for _ in range(round(12.0 / DT)):
        v.step(DT)
        top_speed = max(top_speed, math.hypot(v.vel[0], v.vel[1]))
    assert top_speed == pytest.approx(v.cfg.cruise_speed_ms, abs=0.3)
    assert v.mode == Mode.HOLD
    assert v.pos == pytest.approx([30.0, 0.0, -4.0], abs=0.1)
    assert np.linalg.norm(v.vel) < 0.05


def test_battery_drains_in_flight_and_voltage_follows() -> None:
    v = hovering(2.0)
    full = v.battery_voltage()
    level = v.battery
    run(v, 60.0)
    assert level - v.battery == pytest.approx(60.0 / (v.cfg.battery_flight_minutes * 60.0), rel=0.01)
    assert v.battery_voltage() < full
