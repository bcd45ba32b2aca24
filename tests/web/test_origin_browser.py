"""In a real Chromium: another site's page that knows the token still cannot command the drone (issue 14, 10)."""

from __future__ import annotations

import json

from aiohttp import web

from tests.web.conftest import TOKEN, processor_of
from tests.web.test_page_browser import CHROMIUM, CHROMIUM_ARGS, pytestmark  # noqa: F401 - skip without chromium
from uav_tui.core import UavCore

ATTACK = """
async ([target, token]) => {
  const result = {};
  try {  // a "simple" request: no preflight, the browser sends it and only hides the answer
    await fetch(`${target}/api/command?token=${token}`, {method: "POST", mode: "no-cors",
      headers: {"Content-Type": "text/plain"}, body: JSON.stringify({command: "f 2"})});
    result.fetch = "sent";
  } catch (error) { result.fetch = String(error); }
  result.ws = await new Promise((resolve) => {  // browsers open cross-site websockets freely
    const ws = new WebSocket(`${target.replace("http", "ws")}/ws?token=${token}`);
    ws.onmessage = () => resolve("status received");
    ws.onerror = () => resolve("refused");
    setTimeout(() => resolve("timeout"), 10000);
  });
  return result;
}
"""


async def another_site(request: web.Request) -> web.Response:
    return web.Response(text="<h1>another site</h1>", content_type="text/html")


async def test_a_foreign_page_with_the_token_cannot_command_or_listen(web_core: UavCore) -> None:
    from playwright.async_api import async_playwright

    foreign = web.Application()
    foreign.router.add_get("/", another_site)
    runner = web.AppRunner(foreign)
    await runner.setup()
    site = web.TCPSite(runner, "127.0.0.1", 0)
    await site.start()
    foreign_url = f"http://127.0.0.1:{site._server.sockets[0].getsockname()[1]}/"
    target = f"http://127.0.0.1:{web_core.web.port}"
    try:
        async with async_playwright() as pw:
            browser = await pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                page = await browser.new_page()
                await page.goto(foreign_url)
                result = await page.evaluate(ATTACK, [target, TOKEN])
            finally:
                await browser.close()
    finally:
        await runner.cleanup()
    assert result == {"fetch": "sent", "ws": "refused"}, json.dumps(result)
    assert processor_of(web_core).buttons == []
    refusals = [e.message for e in web_core.events.recent if e.kind == "web" and "not allowed" in e.message]
    assert refusals and foreign_url.rstrip("/") in refusals[0]
