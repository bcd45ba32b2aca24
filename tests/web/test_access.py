"""Token, signalling, status push and page commands over plain HTTP (no browser needed)."""

from __future__ import annotations

import re

import aiohttp
import pytest

from tests.web.conftest import TOKEN, processor_of
from uav_tui.core import UavCore

ENDPOINTS = [("GET", "/"), ("GET", "/static/app.js"), ("POST", "/offer"), ("POST", "/api/roi"),
             ("POST", "/api/command")]


def base(core: UavCore) -> str:
    return f"http://127.0.0.1:{core.web.port}"


def warnings(core: UavCore) -> list[str]:
    return [e.message for e in core.events.recent if e.kind == "web" and e.level == "warning"]


@pytest.mark.parametrize("token", [None, "", "wrong-token", TOKEN + "x"], ids=["none", "empty", "wrong", "longer"])
@pytest.mark.parametrize(("method", "path"), ENDPOINTS, ids=[p for _, p in ENDPOINTS])
async def test_without_the_token_everything_is_401(web_core: UavCore, method: str, path: str,
                                                   token: str | None) -> None:
    params = {} if token is None else {"token": token}
    body = {"rect": [0.1, 0.1, 0.5, 0.5], "command": "f 1", "sdp": "v=0", "type": "offer"}
    async with aiohttp.ClientSession() as http, http.request(method, base(web_core) + path, params=params,
                                                             json=body) as response:
        assert response.status == 401
        assert await response.text() == "401: a valid token is required"
    processor = processor_of(web_core)
    assert processor.rois == [] and processor.buttons == []
    assert web_core.web.video.viewers == 0


async def test_wrong_bearer_header_and_websocket_are_refused(web_core: UavCore) -> None:
    async with aiohttp.ClientSession() as http:
        headers = {"Authorization": "Bearer nope"}
        async with http.post(base(web_core) + "/api/command", json={"command": "f 1"}, headers=headers) as response:
            assert response.status == 401
        for params in ({}, {"token": "nope"}):
            with pytest.raises(aiohttp.WSServerHandshakeError) as refused:
                await http.ws_connect(base(web_core) + "/ws", params=params)
            assert refused.value.status == 401
    assert processor_of(web_core).buttons == []
    assert any("no valid token" in message for message in warnings(web_core))


async def test_page_and_static_files_with_the_token(web_core: UavCore) -> None:
    async with aiohttp.ClientSession(cookie_jar=aiohttp.CookieJar(unsafe=True)) as http:  # unsafe: an IP host
        async with http.get(web_core.web.url) as page:
            assert page.status == 200
            assert '<video id="video"' in await page.text()
        # the page's HttpOnly cookie lets the browser load the script and style sheet
        for name in ("app.js", "style.css"):
            async with http.get(base(web_core) + f"/static/{name}") as asset:
                assert asset.status == 200


async def test_websocket_pushes_status_and_events(web_core: UavCore) -> None:
    async with aiohttp.ClientSession() as http, http.ws_connect(base(web_core) + "/ws",
                                                                params={"token": TOKEN}) as ws:
        seen: dict[str, dict] = {}
        while "status" not in seen:
            message = await ws.receive_json(timeout=5)
            seen[message["type"]] = message
        assert seen["status"]["frame"] == [640, 480]
        assert seen["status"]["status"]["processor"] == "tests.web.conftest:RecordingProcessor"
        web_core.events.emit("warning", "web", "pushed to the page")
        while True:
            message = await ws.receive_json(timeout=5)
            if message["type"] == "event" and message["message"] == "pushed to the page":
                break


@pytest.mark.parametrize("body", [
    b"not json", b"[1, 2]", b'{"sdp": 5, "type": "offer"}', b'{"sdp": "v=0", "type": "answer"}',
    b'{"sdp": "this is not SDP", "type": "offer"}',
    b'{"sdp": "v=0\\r\\no=- 1 1 IN IP4 0.0.0.0\\r\\ns=-\\r\\nt=0 0\\r\\n", "type": "offer"}',
], ids=["text", "array", "sdp-number", "answer", "garbage-sdp", "no-video"])
async def test_malformed_offer_is_400_logged_and_changes_nothing(web_core: UavCore, body: bytes) -> None:
    async with aiohttp.ClientSession() as http, http.post(base(web_core) + "/offer", params={"token": TOKEN},
                                                          data=body) as response:
        assert response.status == 400
    assert warnings(web_core), "the refusal is logged as an event"
    assert web_core.web.video.viewers == 0 and web_core.web.video.source is None
    assert not web_core.web.viewers.peers


@pytest.mark.parametrize("body", [
    b"not json", b'"rect"', b"{}", b'{"rect": [0.1, 0.1, 0.5]}', b'{"rect": [0.1, 0.1, 1.5, 0.5]}',
    b'{"rect": [0.1, "0.1", 0.5, 0.5]}', b'{"rect": [0.1, 0.1, true, 0.5]}', b'{"point": [NaN, 0.5]}',
    b'{"point": [-0.1, 0.5]}', b'{"point": {"x": 0.5}}',
], ids=["text", "string", "empty", "short", "out-of-range", "string-value", "bool", "nan", "negative", "dict"])
async def test_malformed_roi_is_400_logged_and_changes_nothing(web_core: UavCore, body: bytes) -> None:
    async with aiohttp.ClientSession() as http, http.post(base(web_core) + "/api/roi", params={"token": TOKEN},
                                                          data=body) as response:
        assert response.status == 400
    assert any("roi" in message for message in warnings(web_core))
    assert processor_of(web_core).rois == []


async def test_roi_and_commands_reach_the_processor_with_their_origin(web_core: UavCore) -> None:
    headers = {"Authorization": f"Bearer {TOKEN}"}
    async with aiohttp.ClientSession(headers=headers) as http:
        async with http.post(base(web_core) + "/api/roi", json={"rect": [0.55, 0.7, 0.25, 0.3]}) as response:
            assert response.status == 200
        async with http.post(base(web_core) + "/api/roi", json={"point": [0.0, 1.0]}) as response:
            assert response.status == 200
        async with http.post(base(web_core) + "/api/command", json={"command": "f 3"}) as response:
            assert response.status == 200 and (await response.json())["ok"]
        for refused in ("quit", "arm", "autonomy on", "f 5", "nonsense", 7):
            async with http.post(base(web_core) + "/api/command", json={"command": refused}) as response:
                assert response.status == 400, refused
        async with http.post(base(web_core) + "/api/command", json={"command": "hold"}) as response:
            assert response.status == 409  # allowed, but --fc none has no vehicle
            assert "no flight controller" in (await response.json())["message"]
    processor = processor_of(web_core)
    assert processor.rois == [(160, 144, 192, 192), (0, 432, 48, 48)]
    assert processor.buttons == [3]
    assert not web_core.quit_requested.is_set()
    commands = [(e.message, e.origin) for e in web_core.events.recent if e.kind == "command"]
    assert ("roi 160 144 192 192", "web:127.0.0.1") in commands
    assert ("f 3", "web:127.0.0.1") in commands


async def test_every_button_on_the_page_sends_a_command_the_page_may_send(web_core: UavCore) -> None:
    """Each ``data-command`` of the served page is a page command (its script posts it as it is): the processor's
    run, the vehicle's are refused only for want of a vehicle (--fc none), never as not allowed (400)."""
    headers = {"Authorization": f"Bearer {TOKEN}"}
    async with aiohttp.ClientSession(headers=headers) as http:
        async with http.get(base(web_core) + f"/?token={TOKEN}") as response:
            buttons = dict(re.findall(r'<button data-command="([^"]+)"[^>]*>([^<]+)</button>', await response.text()))
        assert {"f 1", "f 4", "precland", "autonomy off", "hold"} <= set(buttons), buttons
        for command, label in buttons.items():
            async with http.post(base(web_core) + "/api/command", json={"command": command}) as response:
                answer = await response.json()
                assert response.status in (200, 409), (label, answer)
                assert response.status == 200 or "no flight controller" in answer["message"], (label, answer)
