"""The simulated vehicle's MAVLink protocol seen from a bare pymavlink ground station: the PX4 rules
MAVSDK hides (offboard needs streaming setpoints, UNSUPPORTED acks, parameter encoding, rates)."""

from __future__ import annotations

import os
import statistics
import struct
import time
from collections.abc import Iterator

import pytest

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402

from controllers.sim.launcher import SimVehicle  # noqa: E402

M = mavutil.mavlink


def ground_station(sim: SimVehicle) -> mavutil.mavfile:
    conn = mavutil.mavlink_connection(
        f"udpin:127.0.0.1:{sim.mavlink_port}", source_system=255, source_component=190, dialect="common"
    )
    assert conn.recv_match(blocking=True, timeout=5) is not None  # also teaches it the vehicle's address
    return conn


@pytest.fixture
def gcs(sim_vehicle: SimVehicle) -> Iterator[mavutil.mavfile]:
    """A ground station on a fresh vehicle."""
    conn = ground_station(sim_vehicle)
    yield conn
    conn.close()


@pytest.fixture(scope="module")
def shared_gcs() -> Iterator[mavutil.mavfile]:
    """A ground station on one vehicle shared by the tests that leave it on the ground."""
    with SimVehicle() as sim:
        conn = ground_station(sim)
        yield conn
        conn.close()


def drain(conn: mavutil.mavfile) -> None:
    """Drop the telemetry queued while nobody read (a full socket buffer would drop the replies)."""
    while conn.recv_msg() is not None:
        pass


def command(conn: mavutil.mavfile, cmd: int, *params: float) -> int:
    """COMMAND_LONG to the autopilot; returns the MAV_RESULT of its ack."""
    p = list(params) + [0.0] * (7 - len(params))
    drain(conn)
    conn.mav.command_long_send(1, 1, cmd, 0, *p)
    deadline = time.monotonic() + 3.0
    while time.monotonic() < deadline:
        ack = conn.recv_match(type="COMMAND_ACK", blocking=True, timeout=0.5)
        if ack is not None and ack.command == cmd:
            assert (ack.target_system, ack.target_component) == (255, 190)
            return ack.result
    raise AssertionError(f"no COMMAND_ACK for command {cmd}")


def receive(conn: mavutil.mavfile, kind: str, timeout: float = 2.0) -> mavutil.mavlink.MAVLink_message | None:
    return conn.recv_match(type=kind, blocking=True, timeout=timeout)


def send_velocity(conn: mavutil.mavfile, vx: float) -> None:
    mask = 0b0000_1101_1100_0111  # velocity + yaw rate
    conn.mav.set_position_target_local_ned_send(0, 1, 1, M.MAV_FRAME_BODY_NED, mask, 0, 0, 0, vx, 0, 0, 0, 0, 0, 0, 0)


def set_mode(conn: mavutil.mavfile, main: int, sub: int = 0) -> int:
    return command(conn, M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, main, sub)


def test_heartbeat_is_px4_quadrotor_with_px4_custom_modes(shared_gcs: mavutil.mavfile) -> None:
    drain(shared_gcs)
    hb = receive(shared_gcs, "HEARTBEAT")
    assert (hb.type, hb.autopilot) == (M.MAV_TYPE_QUADROTOR, M.MAV_AUTOPILOT_PX4)
    assert hb.base_mode & M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED and not hb.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED
    assert hb.custom_mode == (4 << 16) | (3 << 24)  # AUTO.LOITER (HOLD)
    assert set_mode(shared_gcs, 3) == M.MAV_RESULT_ACCEPTED
    hb = receive(shared_gcs, "HEARTBEAT")
    assert hb.custom_mode == 3 << 16  # POSCTL, announced at once
    assert set_mode(shared_gcs, 4, 4) == M.MAV_RESULT_DENIED  # AUTO.MISSION is not simulated


def test_offboard_is_refused_until_setpoints_stream(sim_vehicle: SimVehicle, gcs: mavutil.mavfile) -> None:
    assert set_mode(gcs, 6) == M.MAV_RESULT_DENIED
    send_velocity(gcs, 0.0)
    time.sleep(0.7)  # one old setpoint is not a stream
    assert set_mode(gcs, 6) == M.MAV_RESULT_DENIED
    for _ in range(5):
        send_velocity(gcs, 0.0)
        time.sleep(0.05)
    assert set_mode(gcs, 6) == M.MAV_RESULT_ACCEPTED
    with sim_vehicle.truth(subscribe=False) as truth:
        assert truth.request({"cmd": "state"})["state"]["mode"] == "OFFBOARD"


def test_every_command_is_acked_unknown_ones_unsupported(shared_gcs: mavutil.mavfile) -> None:
    assert command(shared_gcs, M.MAV_CMD_DO_SET_SERVO, 1, 1500) == M.MAV_RESULT_UNSUPPORTED
    assert command(shared_gcs, M.MAV_CMD_NAV_TAKEOFF, *[float("nan")] * 7) == M.MAV_RESULT_DENIED  # not armed
    assert command(shared_gcs, M.MAV_CMD_REQUEST_MESSAGE, 9999) == M.MAV_RESULT_UNSUPPORTED
    assert command(shared_gcs, M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_AUTOPILOT_VERSION) == M.MAV_RESULT_ACCEPTED
    version = receive(shared_gcs, "AUTOPILOT_VERSION")
    assert version.capabilities & M.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE
    assert version.capabilities & M.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_LOCAL_NED


@pytest.mark.parametrize("sim_vehicle", [{"extra_args": ["--gps-delay", "30"]}], indirect=True)
def test_arm_rejected_without_gps_fix(gcs: mavutil.mavfile) -> None:
    assert command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1) == M.MAV_RESULT_TEMPORARILY_REJECTED
    status = receive(gcs, "SYS_STATUS")
    assert not status.onboard_control_sensors_health & M.MAV_SYS_STATUS_SENSOR_GPS
    assert receive(gcs, "GPS_RAW_INT").fix_type < M.GPS_FIX_TYPE_3D_FIX


def test_force_disarm_in_air_drops_the_vehicle(sim_vehicle: SimVehicle, gcs: mavutil.mavfile) -> None:
    truth = sim_vehicle.truth()
    while receive(gcs, "GPS_RAW_INT").fix_type < M.GPS_FIX_TYPE_3D_FIX:
        pass
    assert command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1) == M.MAV_RESULT_ACCEPTED
    alt_amsl = sim_vehicle.home.alt_m + 1.0
    assert command(gcs, M.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, float("nan"), 0, 0, alt_amsl) == M.MAV_RESULT_ACCEPTED
    deadline = time.monotonic() + 5.0
    while not (truth.latest() or {}).get("in_air") and time.monotonic() < deadline:
        time.sleep(0.05)
    assert command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 0) == M.MAV_RESULT_DENIED
    assert command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 0, 21196) == M.MAV_RESULT_ACCEPTED
    text = receive(gcs, "STATUSTEXT")
    assert text is not None and text.text == "Disarmed in the air (forced)"
    deadline = time.monotonic() + 3.0
    while (truth.latest() or {}).get("in_air") and time.monotonic() < deadline:
        time.sleep(0.05)
    state = truth.latest()
    assert not state["armed"] and not state["in_air"] and state["d"] == 0.0


def read_param(conn: mavutil.mavfile, name: str, timeout: float = 2.0) -> mavutil.mavlink.MAVLink_message | None:
    drain(conn)
    conn.mav.param_request_read_send(1, 1, name.encode(), -1)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        msg = conn.recv_match(type="PARAM_VALUE", blocking=True, timeout=0.2)
        if msg is not None and msg.param_id == name:
            return msg
    return None


def test_parameters_read_write_and_bytewise_integers(shared_gcs: mavutil.mavfile) -> None:
    assert read_param(shared_gcs, "MIS_TAKEOFF_ALT").param_value == pytest.approx(2.5)
    drain(shared_gcs)
    shared_gcs.mav.param_set_send(1, 1, b"MIS_TAKEOFF_ALT", 4.0, M.MAV_PARAM_TYPE_REAL32)
    assert receive(shared_gcs, "PARAM_VALUE").param_value == pytest.approx(4.0)
    assert read_param(shared_gcs, "MIS_TAKEOFF_ALT").param_value == pytest.approx(4.0)
    autostart = read_param(shared_gcs, "SYS_AUTOSTART")
    assert autostart.param_type == M.MAV_PARAM_TYPE_INT32
    assert struct.unpack("<i", struct.pack("<f", autostart.param_value))[0] == 10016
    assert read_param(shared_gcs, "NO_SUCH_PARAM", timeout=0.5) is None  # PX4 stays silent


def spacing_ms(conn: mavutil.mavfile, kind: str, count: int = 11) -> float:
    """Median spacing of the next ``count`` ``kind`` messages on the simulator's own clock (time_boot_ms)."""
    stamps: list[int] = []
    deadline = time.monotonic() + 10.0
    while len(stamps) < count:
        assert time.monotonic() < deadline, f"fewer than {count} {kind} within 10 s"
        msg = conn.recv_match(type=kind, blocking=True, timeout=0.5)
        if msg is not None:
            stamps.append(msg.time_boot_ms)
    return statistics.median(b - a for a, b in zip(stamps, stamps[1:], strict=False))


def silent_for_ms(conn: mavutil.mavfile, kind: str, span_ms: int) -> bool:
    """Whether no ``kind`` arrives while the vehicle's clock (read from ATTITUDE_QUATERNION) moves ``span_ms``."""
    start = None
    deadline = time.monotonic() + 10.0
    while time.monotonic() < deadline:
        msg = conn.recv_match(type=[kind, "ATTITUDE_QUATERNION"], blocking=True, timeout=0.5)
        if msg is None:
            continue
        if msg.get_type() == kind:
            return False
        start = msg.time_boot_ms if start is None else start
        if msg.time_boot_ms - start >= span_ms:
            return True
    raise AssertionError("no ATTITUDE_QUATERNION within 10 s")


def test_message_interval_changes_and_stops_a_stream(shared_gcs: mavutil.mavfile) -> None:
    def interval(msg_id: int, us: float) -> int:
        return command(shared_gcs, M.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id, us)

    # Messages after the ack were sent after the change; their spacing is read on the vehicle's clock.
    assert spacing_ms(shared_gcs, "ATTITUDE") < 60  # 50 Hz by default
    assert interval(M.MAVLINK_MSG_ID_ATTITUDE, 100_000) == M.MAV_RESULT_ACCEPTED
    assert spacing_ms(shared_gcs, "ATTITUDE", 6) >= 90  # 10 Hz: never more often
    assert interval(M.MAVLINK_MSG_ID_ATTITUDE, -1) == M.MAV_RESULT_ACCEPTED
    assert silent_for_ms(shared_gcs, "ATTITUDE", 500)
    assert interval(9999, 100_000) == M.MAV_RESULT_DENIED
    assert interval(M.MAVLINK_MSG_ID_ATTITUDE, 0) == M.MAV_RESULT_ACCEPTED
    assert spacing_ms(shared_gcs, "ATTITUDE") < 60  # back to the default


def test_setpoint_arrivals_are_stamped_on_the_shared_monotonic_clock(
    sim_vehicle: SimVehicle, gcs: mavutil.mavfile
) -> None:
    stamps = []
    for vx in (0.1, 0.2, 0.3):
        before = time.monotonic_ns()
        send_velocity(gcs, vx)
        stamps.append((before, time.monotonic_ns()))
        time.sleep(0.05)
    with sim_vehicle.truth(subscribe=False) as truth:
        records = truth.request({"cmd": "setpoints", "since_mono_ns": stamps[0][0] - 1})["records"]
    assert [r["vx"] for r in records] == pytest.approx([0.1, 0.2, 0.3])
    assert all(r["frame"] == M.MAV_FRAME_BODY_NED for r in records)
    for (before, after), record in zip(stamps, records, strict=True):
        assert before - 1_000_000 <= record["t_mono_ns"] <= after + 20_000_000
