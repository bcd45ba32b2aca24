"""A core started on a later event loop of the same thread still takes a browser's offer.

Chromium names its ICE candidates ``<uuid>.local`` (mDNS); aioice resolves them with a per-thread lock that
bound to the first event loop, so every later loop's offer with two such candidates was refused (400) and
the page never got video.
"""

from __future__ import annotations

import asyncio
import uuid

import aiohttp
from aiortc import RTCPeerConnection

from tests.web.conftest import TOKEN, make_core


def mdns_candidates(count: int) -> str:
    """SDP lines for host candidates hidden behind mDNS names, as Chromium sends them."""
    return "".join(f"a=candidate:{n} 1 udp 2113937151 {uuid.uuid4()}.local {50000 + n} typ host\r\n"
                   for n in range(1, count + 1))


async def offer_to_a_new_core() -> tuple[int, str]:
    """Start a core, post it an offer with two mDNS candidates, stop it: the answer's status and text."""
    core = make_core()
    await core.start()
    client = RTCPeerConnection()
    try:
        client.addTransceiver("video", direction="recvonly")
        await client.setLocalDescription(await client.createOffer())
        sdp = client.localDescription.sdp + mdns_candidates(2)  # the last (only) media section is the video
        async with aiohttp.ClientSession() as http, http.post(
                f"http://127.0.0.1:{core.web.port}/offer", params={"token": TOKEN},
                json={"sdp": sdp, "type": "offer"}) as response:
            return response.status, await response.text()
    finally:
        await client.close()
        await core.stop("test finished")


def test_each_event_loop_takes_offers_with_mdns_candidates() -> None:
    for loop_number in (1, 2, 3):
        status, text = asyncio.run(offer_to_a_new_core())
        assert status == 200, f"event loop {loop_number}: {text}"
