"""The page on an open network, from loopback clients (issue 47, 4 and the token point): a DNS-rebinding page's
Origin, an open page while someone guesses from its address, offers that never connect, tokens a URL cannot carry."""

from __future__ import annotations

import asyncio
import itertools
import re
import socket

import aiohttp
import pytest
from aiortc import RTCPeerConnection

from tests.web.conftest import TOKEN
from uav_tui.config import load_config
from uav_tui.core import UavCore
from uav_tui.errors import ConfigError
from uav_tui.web import viewers
from uav_tui.web.throttle import AuthThrottle


def base(core: UavCore, host: str = "127.0.0.1") -> str:
    assert core.web is not None
    return f"http://{host}:{core.web.port}"


async def test_a_rebinding_page_is_refused_and_the_page_own_names_are_not(web_core: UavCore) -> None:
    """The Origin is judged against the address the request reached, never against its own Host header."""
    port = web_core.web.port
    command = {"command": "f 2"}
    async with aiohttp.ClientSession() as http:
        for origin, host, status in ((f"http://evil.example:{port}", f"evil.example:{port}", 403),
                                     (f"http://localhost:{port}", f"localhost:{port}", 200),
                                     (f"http://127.0.0.1:{port}", f"127.0.0.1:{port}", 200)):
            headers = {"Authorization": f"Bearer {TOKEN}", "Origin": origin, "Host": host}
            async with http.post(base(web_core) + "/api/command", json=command, headers=headers) as response:
                assert response.status == status, origin
        with pytest.raises(aiohttp.WSServerHandshakeError) as refused:
            await http.ws_connect(base(web_core) + "/ws", params={"token": TOKEN},
                                  headers={"Origin": f"http://evil.example:{port}", "Host": f"evil.example:{port}"})
        assert refused.value.status == 403


async def test_an_open_page_is_never_locked_out_by_guesses_from_its_address(web_core: UavCore) -> None:
    """Someone on the operator's address (loopback, a shared NAT) guesses without pause: the guesses are
    throttled, and the operator's open page (its session) is answered every time."""
    async with aiohttp.ClientSession(cookie_jar=aiohttp.CookieJar(unsafe=True)) as operator, \
            aiohttp.ClientSession() as guesser:
        async with operator.get(web_core.web.url) as page:
            assert page.status == 200
        guesses: list[int] = []
        stop = asyncio.Event()

        async def guess() -> None:
            while not stop.is_set():
                async with guesser.get(base(web_core) + "/", params={"token": f"guess-{len(guesses)}"}) as response:
                    guesses.append(response.status)

        guessing = asyncio.create_task(guess())
        answers = []
        try:
            for _ in range(20):  # 3 s: the blocks of 1 and 2 s come and go meanwhile
                headers = {"Authorization": f"Bearer {TOKEN}", "Origin": base(web_core)}
                async with operator.post(base(web_core) + "/api/command", json={"command": "f 1"},
                                         headers=headers) as response:
                    answers.append(response.status)
                await asyncio.sleep(0.15)
        finally:
            stop.set()
            await guessing
    assert 429 in guesses and answers == [200] * 20


def test_guessing_without_pause_never_blocks_the_address_over_30_s_in_a_row() -> None:
    """The probe's case on the throttle's own clock: a guess whenever the address is not blocked, for 10 minutes.
    Before, each block was renewed the moment it ended (74 s in a row measured: open for an instant in between);
    now the address is open for 2 s after at most 30 s blocked, so an operator there who retries after
    Retry-After is checked."""
    now, tick = [0.0], 0.01
    throttle = AuthThrottle(clock=lambda: now[0])
    blocked = []
    while now[0] < 600:
        blocked.append(throttle.retry_after("shared") > 0)
        if not blocked[-1]:
            throttle.failed("shared")
        now[0] += tick
    longest = locked = 0.0
    windows = 0
    for is_blocked, run in itertools.groupby(blocked):
        seconds = len(list(run)) * tick
        if is_blocked or seconds < 1.0:  # open for an instant is no way in for the operator
            locked += seconds
        else:
            longest, locked, windows = max(longest, locked), 0.0, windows + 1
    longest = max(longest, locked)
    assert 29.0 < longest <= 30.1 and windows >= 18
    assert throttle.retry_after("operator") == 0  # another address is not touched


async def _offer_that_cannot_connect(http: aiohttp.ClientSession, url: str, deaf_port: int) -> int:
    """POST a real browser-like offer whose only candidate is a UDP port nobody answers; the status."""
    client = RTCPeerConnection()
    try:
        client.addTransceiver("video", direction="recvonly")
        await client.setLocalDescription(await client.createOffer())
        sdp = re.sub(r"a=candidate:[^\r\n]*\r\n", "", client.localDescription.sdp)
        sdp = sdp.replace("a=end-of-candidates", f"a=candidate:1 1 udp 2130706431 127.0.0.1 {deaf_port} typ host"
                          "\r\na=end-of-candidates")
    finally:
        await client.close()
    headers = {"Authorization": f"Bearer {TOKEN}"}
    async with http.post(url + "/offer", json={"sdp": sdp, "type": "offer"}, headers=headers) as response:
        return response.status


async def test_offers_that_never_connect_free_their_viewer_slots(web_core: UavCore,
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(viewers, "VIEWER_CONNECT_TIMEOUT_S", 1.0)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as deaf:
        deaf.bind(("127.0.0.1", 0))
        port = deaf.getsockname()[1]
        async with aiohttp.ClientSession() as http:
            statuses = [await _offer_that_cannot_connect(http, base(web_core), port) for _ in range(5)]
            assert statuses == [200] * 4 + [503]  # four slots taken
            for _ in range(100):
                if web_core.web.video.viewers == 0:
                    break
                await asyncio.sleep(0.05)
            assert web_core.web.video.viewers == 0
            assert await _offer_that_cannot_connect(http, base(web_core), port) == 200
    dropped = [e.message for e in web_core.events.recent if "did not complete" in e.message]
    assert len(dropped) == 4 and dropped[0].startswith("viewer dropped: its connection did not complete within 1 s")


@pytest.mark.parametrize("token", [TOKEN[:16] + " " + TOKEN[16:], TOKEN + "\x1b[2J", TOKEN[:20] + "&x=" + TOKEN[20:]],
                         ids=["space", "escape", "ampersand"])
def test_a_token_a_url_cannot_carry_whole_is_refused(token: str) -> None:
    with pytest.raises(ConfigError, match=r"--web-token may hold only letters, digits and - \. _ ~") as refused:
        load_config(None, {"web_token": token})
    assert "\x1b" not in str(refused.value) and "token_urlsafe(24)" in str(refused.value)


async def test_the_token_is_never_in_an_event(web_core: UavCore) -> None:
    messages = [e.message for e in web_core.events.recent]
    assert any(m.startswith(f"web page on {base(web_core)}/ (its token is on the terminal") for m in messages)
    assert not any("token=" in m or TOKEN in m for m in messages)
