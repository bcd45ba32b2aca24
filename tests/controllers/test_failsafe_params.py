"""The controller checks the autopilot's offboard-loss failsafe at connect and sets what is too slow or does not hold.

PX4: against the simulated vehicle, which serves COM_OF_LOSS_T / COM_OBL_RC_ACT / COM_RC_IN_MODE over the PARAM
protocol, reports a radio in SYS_STATUS only with ``--radio``, and honours them. ArduCopter: against the recording
stand-in serving GUID_TIMEOUT and GUID_OPTIONS (tests marked ``sitl`` in test_sitl_failsafe.py check the real ones).
"""

from __future__ import annotations

import pytest

from controllers.mavsdk.controller import MavsdkController
from controllers.sim.launcher import SimVehicle, free_udp_port
from tests.controllers.fake_autopilot import FakeAutopilot, UdpLink, mavlink

TOO_SLOW = {"extra_args": ["--offboard-loss-timeout", "10", "--offboard-loss-action", "3"]}
"""PX4 flying a dead client's setpoint for 10 s, then returning home instead of stopping."""


async def connected(address: str) -> MavsdkController:
    fc = MavsdkController()
    await fc.connect(address, heartbeat_timeout=5.0)
    return fc


@pytest.mark.parametrize("sim_vehicle", [TOO_SLOW], indirect=True)
async def test_px4_too_slow_failsafe_is_set(sim_vehicle: SimVehicle) -> None:
    fc = await connected(sim_vehicle.connection_string)
    try:
        report = await fc.check_failsafe(2.0, tune=True)
        assert report.ok, report.problems
        assert report.found == {"COM_OF_LOSS_T": 10.0, "COM_OBL_RC_ACT": 3.0}
        assert report.changed == {"COM_OF_LOSS_T": (10.0, 1.0), "COM_OBL_RC_ACT": (3.0, 5.0)}
        again = await fc.check_failsafe(2.0, tune=True)  # read back from the vehicle: it kept them
        assert again.found == {"COM_OF_LOSS_T": 1.0, "COM_OBL_RC_ACT": 5.0} and again.changed == {}
    finally:
        await fc.close()


@pytest.mark.parametrize("sim_vehicle", [TOO_SLOW], indirect=True)
async def test_px4_without_tuning_names_parameter_and_value(sim_vehicle: SimVehicle) -> None:
    fc = await connected(sim_vehicle.connection_string)
    try:
        report = await fc.check_failsafe(2.0, tune=False)
        assert not report.ok and report.changed == {}
        timeout, action = report.problems
        assert timeout.startswith("COM_OF_LOSS_T = 10 ") and "2.5 s" in timeout
        assert action.startswith("COM_OBL_RC_ACT = 3 ") and "set COM_OBL_RC_ACT to 5" in action
        assert (await fc.check_failsafe(2.0, tune=False)).found["COM_OF_LOSS_T"] == 10.0  # left as it was
    finally:
        await fc.close()


async def test_px4_default_position_mode_without_a_radio_is_set_to_hold(sim_vehicle: SimVehicle) -> None:
    """PX4's default offboard-loss action, Position mode, flies sticks nobody holds: SITL sank 4.4 m in 8 s."""
    fc = await connected(sim_vehicle.connection_string)
    try:
        report = await fc.check_failsafe(2.0, tune=True)
        assert report.ok, report.problems
        assert report.found == {"COM_OF_LOSS_T": 1.0, "COM_OBL_RC_ACT": 0.0}
        assert report.changed == {"COM_OBL_RC_ACT": (0.0, 5.0)}
        assert report.radio == "no radio (SYS_STATUS: no RC receiver; COM_RC_IN_MODE=3)"
        assert report.summary() == ("autopilot failsafe: found COM_OF_LOSS_T=1, COM_OBL_RC_ACT=0 (no radio "
                                    "(SYS_STATUS: no RC receiver; COM_RC_IN_MODE=3)); set COM_OBL_RC_ACT 0 -> 5")
        refused = await fc.check_failsafe(2.0, tune=False)  # now Hold: fine without tuning
        assert refused.ok and refused.found["COM_OBL_RC_ACT"] == 5.0
    finally:
        await fc.close()


async def test_px4_position_mode_without_a_radio_refuses_untuned(sim_vehicle: SimVehicle) -> None:
    fc = await connected(sim_vehicle.connection_string)
    try:
        report = await fc.check_failsafe(2.0, tune=False)
    finally:
        await fc.close()
    (problem,) = report.problems
    assert problem.startswith("COM_OBL_RC_ACT = 0 is Position mode, which flies the sticks, and there is no radio")
    assert problem.endswith("(tune_autopilot_failsafe is off): set COM_OBL_RC_ACT to 5")


@pytest.mark.parametrize("sim_vehicle", [{"extra_args": ["--radio"]}], indirect=True)
async def test_px4_position_mode_with_a_radio_is_left_alone(sim_vehicle: SimVehicle) -> None:
    fc = await connected(sim_vehicle.connection_string)
    try:
        report = await fc.check_failsafe(2.0, tune=True)
    finally:
        await fc.close()
    assert report.ok and report.changed == {}
    assert report.found == {"COM_OF_LOSS_T": 1.0, "COM_OBL_RC_ACT": 0.0}
    assert report.radio == "radio connected (SYS_STATUS: RC receiver present; COM_RC_IN_MODE=3)"


@pytest.mark.parametrize("tune", [True, False], ids=["tune", "report-only"])
async def test_ardupilot_guid_timeout(tune: bool) -> None:
    port = free_udp_port()
    with FakeAutopilot(UdpLink(port), mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA) as fake:
        fake.params["GUID_TIMEOUT"] = 3.0  # ArduCopter's default: 3.8 s of flight after a SIGKILL
        fake.params["GUID_OPTIONS"] = 0  # ArduCopter's default
        fc = await connected(f"udpin://127.0.0.1:{port}")
        try:
            report = await fc.check_failsafe(2.0, tune=tune)
        finally:
            await fc.close()
    assert report.found["GUID_TIMEOUT"] == 3.0
    if tune:
        assert report.ok and report.changed == {"GUID_TIMEOUT": (3.0, 1.0)}
        assert fake.params["GUID_TIMEOUT"] == 1.0
    else:
        (problem,) = report.problems
        assert problem.startswith("GUID_TIMEOUT = 3 ") and "tune_autopilot_failsafe is off" in problem
        assert fake.params["GUID_TIMEOUT"] == 3.0


async def test_ardupilot_guided_options_that_stop_holding_are_cleared() -> None:
    port = free_udp_port()
    with FakeAutopilot(UdpLink(port), mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA) as fake:
        fake.params["GUID_TIMEOUT"] = 1.0
        fake.params["GUID_OPTIONS"] = 1 | 16 | 32  # arming from the transmitter; position and velocity not stabilised
        fc = await connected(f"udpin://127.0.0.1:{port}")
        try:
            report = await fc.check_failsafe(2.0, tune=True)
        finally:
            await fc.close()
    assert report.ok, report.problems
    assert report.changed == {"GUID_OPTIONS": (49.0, 1.0)} and fake.params["GUID_OPTIONS"] == 1  # the rest kept


async def test_unreadable_parameter_is_a_problem() -> None:
    port = free_udp_port()
    with FakeAutopilot(UdpLink(port), mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA) as fake:  # serves no GUID_TIMEOUT
        fc = await connected(f"udpin://127.0.0.1:{port}")
        try:
            report = await fc.check_failsafe(2.0, tune=True)
        finally:
            await fc.close()
    assert not fake.params
    assert [p.split(":")[0] for p in report.problems] == ["could not read GUID_TIMEOUT", "could not read GUID_OPTIONS"]
