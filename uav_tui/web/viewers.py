"""The page's video viewers: one WebRTC peer connection each, at most :data:`MAX_VIEWERS`, and a slot freed when
its connection never completes.

A browser's offer gets an answer with the processed video track (one :class:`~uav_tui.web.tracks.VideoHub`
subscription); a peer whose connection (ICE, DTLS) has not completed :data:`VIEWER_CONNECT_TIMEOUT_S` after its
offer is closed, so offers that cannot connect (a firewall, another network, a hostile client) do not hold the
slots for the rest of the run.
"""

from __future__ import annotations

import asyncio
from typing import Any

from aiortc import RTCConfiguration, RTCPeerConnection, RTCSessionDescription

from uav_tui.events import EventLog
from uav_tui.output.text import shorten
from uav_tui.web.tracks import VideoHub

MAX_VIEWERS = 4
"""Peer connections served at once; each one encodes its own stream."""
VIEWER_CONNECT_TIMEOUT_S = 6.0
"""A viewer's connection (ICE, DTLS) must complete this long after its offer, else its slot is freed (on a LAN it
takes well under a second)."""


class ViewersFull(Exception):
    """Every viewer slot is taken."""


class Viewers:
    """The peer connections that stream ``video``; viewers coming and going are said in ``events``."""

    def __init__(self, video: VideoHub, events: EventLog) -> None:
        self.video = video
        self.events = events
        self.peers: set[RTCPeerConnection] = set()
        self._pending: dict[RTCPeerConnection, asyncio.Task[None]] = {}
        """Viewers whose connection has not completed yet, each with the task that drops it when it does not."""

    async def answer(self, sdp: str, origin: str) -> RTCSessionDescription:
        """The answer to the offer ``sdp`` from ``origin``.

        Raises:
            ViewersFull: MAX_VIEWERS are watching.
            ValueError: the offer cannot be taken (what aiortc said).
        """
        if len(self.peers) >= MAX_VIEWERS:
            raise ViewersFull(f"{MAX_VIEWERS} viewers are watching already")
        pc = RTCPeerConnection(RTCConfiguration(iceServers=[]))  # loopback / LAN only: no STUN lookups
        self.peers.add(pc)
        track = None
        try:
            await pc.setRemoteDescription(RTCSessionDescription(sdp=sdp, type="offer"))
            if not any(t.kind == "video" for t in pc.getTransceivers()):
                raise ValueError("the offer has no video section")
            track = self.video.subscribe()
            pc.addTrack(track)
            await pc.setLocalDescription(await pc.createAnswer())
        except Exception as exc:  # noqa: BLE001 - aiortc raises many types for a bad SDP
            await self._close(pc, track)
            raise ValueError(f"offer rejected: {type(exc).__name__}: {shorten(str(exc), 200)}") from None

        @pc.on("connectionstatechange")
        async def on_state() -> None:
            if pc.connectionState == "connected" and (pending := self._pending.pop(pc, None)) is not None:
                pending.cancel()
            if pc.connectionState in ("failed", "closed") and pc in self.peers:  # once, not again on close
                await self._close(pc, track)
                self.events.emit("info", "web", f"viewer left ({self.video.viewers} watching)", origin)

        self._pending[pc] = asyncio.create_task(self._drop_unconnected(pc, track, origin),
                                                name=f"viewer from {origin} connecting")
        self.events.emit("info", "web", f"viewer connected ({self.video.viewers} watching)", origin)
        return pc.localDescription

    async def close(self) -> None:
        """Close every peer connection and the video hub."""
        for pending in self._pending.values():
            pending.cancel()
        self._pending.clear()
        peers = tuple(self.peers)
        self.peers.clear()
        await asyncio.gather(*(pc.close() for pc in peers), return_exceptions=True)
        self.video.close()

    async def _drop_unconnected(self, pc: RTCPeerConnection, track: Any, origin: str) -> None:
        """Free the slot of a viewer whose connection has not completed in VIEWER_CONNECT_TIMEOUT_S."""
        await asyncio.sleep(VIEWER_CONNECT_TIMEOUT_S)
        self._pending.pop(pc, None)
        if pc in self.peers and pc.connectionState != "connected":
            await self._close(pc, track)
            self.events.emit("warning", "web", f"viewer dropped: its connection did not complete within "
                             f"{VIEWER_CONNECT_TIMEOUT_S:g} s (a firewall, or another network); "
                             f"{self.video.viewers} watching", origin)

    async def _close(self, pc: RTCPeerConnection, track: Any) -> None:
        self.peers.discard(pc)
        if (pending := self._pending.pop(pc, None)) is not None and pending is not asyncio.current_task():
            pending.cancel()
        if track is not None:
            self.video.unsubscribe(track)
        await pc.close()
