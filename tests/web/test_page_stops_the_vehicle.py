"""The page's two stop buttons reach a vehicle flying under autonomy.

Each button's command is read from the page as served and posted the way its script posts it (the
page's HTTP API, token and same-origin header), so this runs without a browser. What the vehicle did
is read from the simulator's ground truth, not from the platform's log.
"""

from __future__ import annotations

import asyncio
import re
from pathlib import Path

import aiohttp
import pytest

from tests.core.flight_helpers import fly_under_autonomy, flying_core, moving, setpoints_since, speed, wait_until
from tests.web.conftest import TOKEN, free_port


async def button_command(http: aiohttp.ClientSession, base: str, label: str) -> str:
    """The command the served page's button ``label`` sends."""
    async with http.get(f"{base}/?token={TOKEN}") as response:
        page = await response.text()
    found = re.search(rf'<button data-command="([^"]+)"[^>]*>{re.escape(label)}</button>', page)
    assert found, f"no {label!r} button on the page"
    return found.group(1)


@pytest.mark.parametrize("label", ["Autonomy off", "Hold"])
async def test_stop_buttons_hold_the_vehicle_autonomy_flies(tmp_path: Path, label: str) -> None:
    port = free_port()
    base = f"http://127.0.0.1:{port}"
    web = {"web": True, "web_host": "127.0.0.1", "web_port": port, "web_token": TOKEN}
    headers = {"Authorization": f"Bearer {TOKEN}", "Origin": base}
    async with flying_core(tmp_path, **web) as core, aiohttp.ClientSession() as http:
        truth = core.truth
        command = await button_command(http, base, label)
        await fly_under_autonomy(core, lambda: truth.latest()["mode"] == "OFFBOARD" and speed(truth.latest()) > 0.4,
                                 "autonomy flying the vehicle")
        async with http.post(f"{base}/api/command", json={"command": command}, headers=headers) as response:
            assert response.status == 200, await response.text()
        # The reply comes after the command ran: autonomy is off and the vehicle already holds.
        assert not core.gate.enabled
        held = await asyncio.to_thread(truth.wait_latest)
        assert held["mode"] == "HOLD"
        held_ns = held["t_mono_ns"]
        await wait_until(lambda: speed(truth.latest()) < 0.15, 5, "the vehicle to stop")
        executed = core.gate.executed
        await asyncio.sleep(1.0)  # the processor still asks to fly forward
        assert core.gate.executed == executed and truth.latest()["mode"] == "HOLD"
        assert moving(await setpoints_since(truth, held_ns)) == []  # nothing moves it after the hold
        assert any(e.kind == "command" and e.origin == "web:127.0.0.1" for e in core.events.recent)
