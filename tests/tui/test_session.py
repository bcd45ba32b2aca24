"""What a lost terminal does to a flying vehicle: hold and exit, or carry on headless (``--on-hangup``)."""

from __future__ import annotations

import asyncio
import time
from types import SimpleNamespace

import pytest

from tests.core.flight_helpers import (
    NO_FAILSAFE,
    fly_under_autonomy,
    setpoints_since,
    speed,
    steering_config,
    take_off,
    wait_until,
)
from uav_tui.core import CoreState
from uav_tui.headless import EXIT_UNHANDLED_ERROR
from uav_tui.tui import _session
from uav_tui.tui._session import TuiSession

from .conftest import started, wait_for


def messages(session: TuiSession) -> list[str]:
    return [event.message for event in session.core.events.recent]


@pytest.mark.parametrize("sim_vehicle", [NO_FAILSAFE], indirect=True)
async def test_hangup_holds_the_vehicle_autonomy_flies_then_exits(tmp_path, sim_vehicle):
    config = steering_config(tmp_path, fc=sim_vehicle.connection_string)
    session = TuiSession(config, on_hangup="stop")
    truth = sim_vehicle.truth()
    async with session.app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        await take_off(session.core, truth)
        await fly_under_autonomy(session.core, lambda: truth.latest()["mode"] == "OFFBOARD", "autonomy flying")
        session._hangup("SIGHUP")  # what TerminalWatch reports (without detaching pytest from its terminal)
        await wait_for(pilot, lambda: session.core.state is CoreState.STOPPED, timeout=15, what="the core to stop")
    stopped = time.monotonic_ns()
    assert any("terminal lost (SIGHUP)" in m for m in messages(session))
    assert truth.wait_latest()["mode"] == "HOLD"  # the simulator's failsafe is off: this hold is uav-tui's
    await wait_until(lambda: speed(truth.latest()) < 0.15, 5, "the vehicle to stop")
    await asyncio.sleep(0.5)
    assert await setpoints_since(truth, stopped) == []


async def test_hangup_with_continue_keeps_the_core_running_until_quit(make_config):
    session = TuiSession(make_config(fc="sim"), on_hangup="continue")
    async with session.app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        session._hangup("SIGHUP")
        await wait_for(pilot, lambda: not session.app.is_running, what="the screen to close")
    assert session.headless and session.core.state is CoreState.RUNNING
    processed = session.core.worker.snapshot().frames_processed
    headless = asyncio.create_task(session._run_headless())
    await asyncio.sleep(0.5)
    assert not headless.done()
    assert session.core.worker.snapshot().frames_processed > processed  # it keeps processing
    await session.core.execute("quit", origin="web")  # e.g. from the web page
    await asyncio.wait_for(headless, 5)
    assert session.reason == "quit"
    await session.core.stop(session.reason)


@pytest.mark.parametrize("sim_vehicle", [NO_FAILSAFE], indirect=True)
async def test_an_unhandled_error_holds_the_flying_vehicle_and_exits_with_status_3(tmp_path, sim_vehicle):
    session = TuiSession(steering_config(tmp_path, fc=sim_vehicle.connection_string))
    truth = sim_vehicle.truth()
    async with session.app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        await take_off(session.core, truth)
        await fly_under_autonomy(session.core, lambda: truth.latest()["mode"] == "OFFBOARD", "autonomy flying")

        def buggy_listener(result) -> None:
            raise KeyError("a bug in a frame listener")

        session.core.add_frame_listener(buggy_listener)
        await wait_for(pilot, lambda: session.core.state is CoreState.STOPPED, timeout=15, what="the core to stop")
    stopped = time.monotonic_ns()
    assert session.app.return_code == EXIT_UNHANDLED_ERROR
    assert session.app.stop_reason.startswith("unhandled error in frame")
    assert truth.wait_latest()["mode"] == "HOLD"
    await wait_until(lambda: speed(truth.latest()) < 0.15, 5, "the vehicle to stop")
    await asyncio.sleep(0.5)
    assert await setpoints_since(truth, stopped) == []


def test_the_saved_run_note_shows_a_hostile_runs_dir_escaped(tmp_path, capsys, monkeypatch):
    """The note run_tui prints after the dashboard: the runs_dir comes from outside (config, command line)."""
    run_dir = tmp_path / "runs\x1b]2;pwned\x07\x1b[2J" / "2026-11-27T14-00-00Z"
    core = SimpleNamespace(recorder=SimpleNamespace(run_dir=run_dir))

    class Ended:
        def __init__(self, *args, **kwargs):
            self.core = core

        async def run(self):
            return 0

    monkeypatch.setattr(_session, "TuiSession", Ended)  # the dashboard itself needs a terminal
    assert _session.run_tui(None) == 0
    printed = capsys.readouterr().out
    assert "runs\\x1b]2;pwned\\x07\\x1b[2J" in printed and not {"\x1b", "\x07"} & set(printed)
