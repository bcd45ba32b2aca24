"""The web page shows a lost link and a stalled camera: the status line says the telemetry is stale or the
camera STALLED, the events list has loss and recovery (real headless Chromium; the simulator frozen with SIGSTOP
and resumed, a real MJPEG stream over HTTP that hangs and comes back)."""

from __future__ import annotations

import contextlib
import os
import signal
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest

from controllers.sim.launcher import SimVehicle
from tests.sources.stream_servers import MjpegTestServer
from tests.web.conftest import make_core
from tests.web.test_page_browser import CHROMIUM, CHROMIUM_ARGS
from uav_tui.core import UavCore
from uav_tui.headless import format_status

pytestmark = pytest.mark.skipif(not Path(CHROMIUM).exists(), reason="needs Debian's chromium (apt install chromium)")

STATUS = "document.getElementById('status').textContent"
EVENTS = "document.getElementById('events').textContent"


@contextlib.asynccontextmanager
async def page_of(**settings: Any) -> AsyncIterator[tuple[UavCore, Any]]:
    """A started core with these settings and its page open in headless Chromium; both closed after."""
    from playwright.async_api import async_playwright

    core = make_core(**settings)
    await core.start()
    try:
        async with async_playwright() as pw:
            browser = await pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            page = await browser.new_page()
            await page.goto(core.web.url)
            yield core, page
            await browser.close()
    finally:
        await core.stop()


async def test_link_loss_and_recovery_on_the_page(sim_vehicle: SimVehicle) -> None:
    async with page_of(fc=sim_vehicle.connection_string) as (_core, page):
        await page.wait_for_function(f"{STATUS}.includes('disarmed')", timeout=20000)
        assert "stale" not in await page.evaluate(STATUS)
        os.kill(sim_vehicle.pid, signal.SIGSTOP)
        try:
            await page.wait_for_function(f"{STATUS}.includes('LINK LOST, stale:')", timeout=20000)
            await page.wait_for_function(f"{EVENTS}.includes('link lost: no heartbeat')", timeout=20000)
        finally:
            os.kill(sim_vehicle.pid, signal.SIGCONT)
        await page.wait_for_function(f"{EVENTS}.includes('link restored after')", timeout=20000)
        await page.wait_for_function(f"!{STATUS}.includes('stale')", timeout=20000)


async def test_a_stalled_camera_on_the_page_and_the_headless_line(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("sources.base.RETRY_DELAYS_S", (0.05, 0.1, 0.2))
    server = MjpegTestServer()
    server.start()
    try:
        async with page_of(source=server.url) as (core, page):
            await page.wait_for_function(f"{STATUS}.includes('320x240 cam')", timeout=20000)
            server.frozen.set()  # the connection stays open, no frame comes: the camera hangs
            # Before: only 'cam 0.0' and a growing age said so.
            await page.wait_for_function(f"{STATUS}.includes('320x240 camera STALLED cam')", timeout=20000)
            assert " STALLED proc " in format_status(core.status(), 1.0)
            server.frozen.clear()
            await page.wait_for_function(f"!{STATUS}.includes('STALLED')", timeout=30000)
            assert "STALLED" not in format_status(core.status(), 1.0)
    finally:
        server.stop()
