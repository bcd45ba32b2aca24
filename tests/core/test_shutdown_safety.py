"""Safety rule 6: SIGTERM / SIGHUP / an unhandled error hold the vehicle before uav-tui exits; after SIGKILL
the autopilot's offboard-loss failsafe holds it. The simulator runs on its own and outlives uav-tui."""

from __future__ import annotations

import asyncio
import io
import json
import signal
import time
from pathlib import Path

import pytest

from controllers.sim.launcher import SimVehicle
from tests.core.flight_helpers import (
    NO_FAILSAFE,
    fly_under_autonomy,
    setpoints_since,
    speed,
    start_steering_flight,
    steering_config,
    take_off,
    wait_for,
    wait_until,
)
from uav_tui.core import CoreState
from uav_tui.headless import EXIT_UNHANDLED_ERROR, HeadlessRunner
from uav_tui.hosting.host import ProcessedFrame

SCRIPT = "arm\ntakeoff 3\nwait 6\nf 1\nautonomy on\nwait 120\n"


@pytest.fixture
def flying_uav(tmp_path: Path, sim_vehicle: SimVehicle):
    """uav-tui flying the simulator under autonomy (the test processor streams forward vectors)."""
    process = start_steering_flight(tmp_path, sim_vehicle.connection_string, SCRIPT)
    truth = sim_vehicle.truth()
    try:
        wait_for(lambda: (s := truth.latest()) is not None and s["mode"] == "OFFBOARD" and speed(s) > 0.3, 40,
                 "uav-tui to fly a vector")
        yield process, truth
    finally:
        process.kill()
        process.communicate()
        truth.close()


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP], ids=["SIGTERM", "SIGHUP"])
@pytest.mark.parametrize("sim_vehicle", [NO_FAILSAFE], indirect=True)
def test_signal_during_a_vector_holds_before_exit(flying_uav, signum: int) -> None:
    process, truth = flying_uav
    process.send_signal(signum)
    out, _ = process.communicate(timeout=20)
    exited = time.monotonic_ns()
    assert process.returncode == 0, out
    assert "vehicle put in hold before exit" in out
    state = truth.wait_latest()
    assert state["mode"] == "HOLD"  # held by uav-tui itself, before it exited
    wait_for(lambda: speed(truth.latest()) < 0.15, 3, "the vehicle to stop")
    time.sleep(0.5)
    late = truth.request({"cmd": "setpoints", "since_mono_ns": exited})["records"]
    assert late == []  # nothing it started keeps streaming setpoints


@pytest.mark.parametrize(("command", "reported", "mode"), [("land", "LAND", "LAND"),
                                                        ("rtl", "RETURN_TO_LAUNCH", "RTL")])
@pytest.mark.parametrize("then", ["wait 1\n", ""], ids=["mode-reported", "exit-at-once"])
def test_exit_leaves_a_landing_or_returning_vehicle_to_it(tmp_path: Path, sim_vehicle: SimVehicle, command: str,
                                                         reported: str, mode: str, then: str) -> None:
    """A script ending with ``land`` (or quitting, or the SSH session dropping, while the vehicle lands or a
    failsafe brings it home) must not leave it hovering where a hold before exit would stop it. Also when it
    exits as soon as the command is acknowledged, before the autopilot's next heartbeat reports the new mode
    (it did: PX4 SITL hovered in HOLD)."""
    truth = sim_vehicle.truth()
    process = start_steering_flight(tmp_path, sim_vehicle.connection_string,
                                    f"arm\ntakeoff 5\nwait 8\n{command}\n{then}")
    try:
        out, _ = process.communicate(timeout=60)
        exited_alt = -truth.wait_latest()["d"]
        assert process.returncode == 0, out
        assert f"vehicle left in {reported} mode at exit: a hold would interrupt it" in out, out
        assert "vehicle put in hold before exit" not in out
        assert exited_alt > 2, "the vehicle was still flying when uav-tui exited"
        wait_for(lambda: -truth.latest()["d"] < exited_alt - 0.5 or -truth.latest()["d"] > exited_alt + 0.5, 10,
                 f"the vehicle to go on {'landing' if command == 'land' else 'returning'} after the exit")
        assert truth.latest()["mode"] == mode
    finally:
        process.kill()
        process.communicate()
        truth.close()


def test_sigkill_leaves_the_autopilot_failsafe_to_hold(flying_uav) -> None:
    process, truth = flying_uav
    process.send_signal(signal.SIGKILL)
    process.communicate(timeout=10)
    killed = time.monotonic()
    wait_for(lambda: truth.latest()["mode"] == "HOLD", 3, "the simulator's offboard-loss failsafe")
    assert time.monotonic() - killed < 3
    wait_for(lambda: speed(truth.latest()) < 0.15, 3, "the vehicle to stop")


@pytest.mark.parametrize("sim_vehicle", [NO_FAILSAFE], indirect=True)
async def test_an_unhandled_error_holds_the_flying_vehicle_then_exits_non_zero(
    tmp_path: Path, sim_vehicle: SimVehicle
) -> None:
    truth = sim_vehicle.truth()
    out = io.StringIO()
    runner = HeadlessRunner(steering_config(tmp_path, fc=sim_vehicle.connection_string), out=out)
    run = asyncio.create_task(runner.run())
    try:
        core = runner.core
        await wait_until(lambda: core.state is CoreState.RUNNING, 30, "the platform to start")
        await take_off(core, truth)
        await fly_under_autonomy(core, lambda: truth.latest()["mode"] == "OFFBOARD" and speed(truth.latest()) > 0.4,
                                 "autonomy flying the vehicle")

        def buggy_interface(result: ProcessedFrame) -> None:
            raise ZeroDivisionError("a bug in a frame listener")

        core.add_frame_listener(buggy_interface)
        code = await asyncio.wait_for(asyncio.shield(run), 20)
        exited = time.monotonic_ns()
    finally:
        if not run.done():
            run.cancel()
            await asyncio.gather(run, return_exceptions=True)
    assert code == EXIT_UNHANDLED_ERROR
    assert "unhandled error in frame" in out.getvalue() and "ZeroDivisionError" in out.getvalue()
    assert "vehicle put in hold before exit" in out.getvalue()
    assert truth.wait_latest()["mode"] == "HOLD"
    await wait_until(lambda: speed(truth.latest()) < 0.15, 3, "the vehicle to stop")
    await asyncio.sleep(0.5)
    assert await setpoints_since(truth, exited) == []  # nothing it started keeps streaming


async def test_a_part_that_fails_to_stop_is_reported_and_the_rest_is_still_released(tmp_path: Path) -> None:
    """A bug in releasing one part (here the processor's) must not leave the camera open or the dataset unfinished."""
    out = io.StringIO()
    runner = HeadlessRunner(steering_config(tmp_path, fc="none", record=True, runs_dir=str(tmp_path / "runs")),
                            out=out)
    run = asyncio.create_task(runner.run())
    core = runner.core
    await wait_until(lambda: core.state is CoreState.RUNNING and core.worker.last is not None, 30, "frames")

    def broken_close() -> None:
        raise RuntimeError("a bug while stopping")

    core.worker.close = broken_close
    runner.request_stop("test")
    code = await asyncio.wait_for(run, 20)
    assert code == EXIT_UNHANDLED_ERROR
    assert "unhandled error in the processor task: RuntimeError('a bug while stopping')" in out.getvalue()
    assert core.state is CoreState.STOPPED
    assert not core.source.get_properties()["running"]  # released after the part that failed
    run_json = json.loads((core.recorder.run_dir / "run.json").read_text())
    assert "end_wall_ns" in run_json  # the dataset was finished
