"""The web page shows a lost link: the status line says the telemetry is stale, the events list has loss and
recovery (real headless Chromium, simulator frozen with SIGSTOP and resumed)."""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest

from controllers.sim.launcher import SimVehicle
from tests.web.conftest import make_core
from tests.web.test_page_browser import CHROMIUM, CHROMIUM_ARGS

pytestmark = pytest.mark.skipif(not Path(CHROMIUM).exists(), reason="needs Debian's chromium (apt install chromium)")

STATUS = "document.getElementById('status').textContent"
EVENTS = "document.getElementById('events').textContent"


async def test_link_loss_and_recovery_on_the_page(sim_vehicle: SimVehicle) -> None:
    from playwright.async_api import async_playwright

    core = make_core(fc=sim_vehicle.connection_string)
    await core.start()
    try:
        async with async_playwright() as pw:
            browser = await pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            page = await browser.new_page()
            await page.goto(core.web.url)
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
            await browser.close()
    finally:
        await core.stop()
