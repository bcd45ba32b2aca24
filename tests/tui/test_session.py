"""What a lost terminal does to a flying vehicle: hold and exit, or carry on headless (``--on-hangup``)."""

from __future__ import annotations

import asyncio

from uav_tui.core import CoreState
from uav_tui.tui._session import TuiSession

from .conftest import started, wait_for


def messages(session: TuiSession) -> list[str]:
    return [event.message for event in session.core.events.recent]


async def fly(pilot, session: TuiSession) -> None:
    await started(pilot)
    await session.core.execute("arm", origin="test")
    await session.core.execute("takeoff 3", origin="test")
    await wait_for(pilot, lambda: session.core.telemetry.snapshot().in_air, timeout=30, what="the vehicle in the air")


async def test_hangup_holds_the_flying_vehicle_then_exits(make_config):
    session = TuiSession(make_config(fc="sim"), on_hangup="stop")
    async with session.app.run_test(size=(80, 24)) as pilot:
        await fly(pilot, session)
        session._hangup("SIGHUP")  # what TerminalWatch reports (without detaching pytest from its terminal)
        await wait_for(pilot, lambda: session.core.state is CoreState.STOPPED, timeout=15, what="the core to stop")
    assert "vehicle put in hold before exit" in messages(session)
    assert any("terminal lost (SIGHUP)" in m for m in messages(session))


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
