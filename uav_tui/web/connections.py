"""How many connections the page takes, from one address and in all, so that no one on the network can use up the
platform's file descriptors.

Every connection costs a descriptor, and the recorder, the camera and a restarting processor need theirs: at
start, :func:`connection_budget` gives the page what the descriptor limit (``RLIMIT_NOFILE``) leaves after the
descriptors already open and :data:`FD_RESERVE` kept for the rest of the run, at most :data:`MAX_CONNECTIONS`.
:class:`LimitedServer` (aiohttp's connection manager) closes a connection at once when its address holds
:data:`PER_ADDRESS` already, or the page holds its budget; the last :data:`OPERATOR_HEADROOM` of it are kept for
addresses that showed the token (:meth:`ConnectionLimits.trust`), so a crowd of strangers cannot take the
operator's page; at most :data:`BACKLOG` wait to be judged. Idle connections (also one that never completes its
request) are closed by aiohttp after ``keepalive_timeout`` (:data:`IDLE_TIMEOUT_S`).
"""

from __future__ import annotations

import asyncio
import logging
import os
import resource
import time
from collections import Counter
from typing import Any

from aiohttp import web
from aiohttp.web_protocol import RequestHandler

from uav_tui.events import EventLog

logger = logging.getLogger(__name__)

IDLE_TIMEOUT_S = 5.0
"""A connection with no request in progress for this long is closed (aiohttp's ``keepalive_timeout``, which also
covers the time to send a first request: a client that connects and sends nothing, or a header a byte a second)."""
BODY_TIMEOUT_S = 10.0
"""A request body (at most 256 kB) not received in this long is refused (408)."""
MAX_CONNECTIONS = 64
"""The page's connections in all, at most (a browser opens up to 6 to a host, plus the websocket)."""
PER_ADDRESS = 16
"""Connections one address may hold."""
OPERATOR_HEADROOM = 8
"""Connections of the budget only addresses that showed the token may take."""
FD_RESERVE = 64
"""Descriptors left to the rest of the platform whatever the page does: the recorder's files, a restarted processor's
pipes and shared memory, the camera, a viewer's UDP sockets."""
BACKLOG = 16
"""Connections the kernel queues for the page, and so the most asyncio accepts at once (each holds a descriptor
until the page has judged it): a flood waits in the kernel, not in the platform's descriptors."""
TRUST_S = 600.0
"""How long an address that showed the token counts as the operator's."""


def connection_budget() -> int:
    """Connections the page may hold: what the descriptor limit leaves after those open now, FD_RESERVE and a
    BACKLOG being judged."""
    soft, _ = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft == resource.RLIM_INFINITY:
        return MAX_CONNECTIONS
    try:
        open_now = len(os.listdir("/proc/self/fd"))
    except OSError:  # no /proc: count none open (the reserve still applies)
        open_now = 0
    return max(OPERATOR_HEADROOM, min(MAX_CONNECTIONS, soft - open_now - FD_RESERVE - BACKLOG))


class ConnectionLimits:
    """Counts the page's connections per client address and decides whether a new one is taken.

    Args:
        budget: connections in all (:func:`connection_budget`).
        events: where refusals are said (the first, then a count at most once a minute).
    """

    def __init__(self, budget: int, events: EventLog) -> None:
        self.budget = budget
        self.events = events
        self.refused = 0
        """Connections closed at once so far."""
        self._open: Counter[str] = Counter()
        self._trusted: dict[str, float] = {}
        self._said_at = -TRUST_S
        self._said_count = 0

    @property
    def open(self) -> int:
        """Connections held now."""
        return sum(self._open.values())

    def trust(self, address: str) -> None:
        """``address`` showed the token: it may take the operator's headroom for TRUST_S."""
        if len(self._trusted) > 256:
            self._trusted.clear()
        self._trusted[address] = time.monotonic()

    def admit(self, address: str) -> bool:
        """Whether a new connection from ``address`` is taken (then counted until :meth:`release`)."""
        trusted = time.monotonic() - self._trusted.get(address, -TRUST_S) < TRUST_S
        room = self.budget if trusted else self.budget - OPERATOR_HEADROOM
        if self._open[address] >= PER_ADDRESS or self.open >= room:
            self._refuse(address)
            return False
        self._open[address] += 1
        return True

    def release(self, address: str) -> None:
        self._open[address] -= 1
        if self._open[address] <= 0:
            del self._open[address]

    def _refuse(self, address: str) -> None:
        self.refused += 1
        now = time.monotonic()
        if now - self._said_at >= 60.0:
            since = f" ({self.refused - self._said_count} since the last said)" if self._said_count else ""
            self.events.emit("warning", "web", f"closing new connections from {address} and others beyond "
                             f"{PER_ADDRESS} an address or {self.budget} in all{since}; the operator's address keeps "
                             f"{OPERATOR_HEADROOM} of them", f"web:{address}")
            self._said_at, self._said_count = now, self.refused


class LimitedServer(web.Server):
    """aiohttp's connection manager, closing at once the connections :class:`ConnectionLimits` does not take."""

    def __init__(self, *args: Any, limits: ConnectionLimits, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.limits = limits
        self._addresses: dict[RequestHandler, str] = {}

    def connection_made(self, handler: RequestHandler, transport: asyncio.Transport) -> None:
        super().connection_made(handler, transport)
        peer = transport.get_extra_info("peername")
        address = str(peer[0]) if isinstance(peer, tuple) and peer else "?"
        if self.limits.admit(address):
            self._addresses[handler] = address
        else:  # closed once aiohttp has set the connection up (closing it from inside its setup breaks it)
            asyncio.get_running_loop().call_soon(handler.force_close)

    def connection_lost(self, handler: RequestHandler, exc: BaseException | None = None) -> None:
        if (address := self._addresses.pop(handler, None)) is not None:
            self.limits.release(address)
        super().connection_lost(handler, exc)


class AcceptFailures:
    """Says once that the listening socket cannot accept (no descriptors left), instead of asyncio's traceback for
    every attempt (thousands a second under a flood), and the count when the page stops.

    Installed as the loop's exception handler while the page serves; every other context goes to the handler
    that was there before (or asyncio's default).
    """

    def __init__(self, events: EventLog) -> None:
        self.events = events
        self.count = 0
        self._loop: asyncio.AbstractEventLoop | None = None
        self._previous: Any = None

    def install(self, loop: asyncio.AbstractEventLoop) -> None:
        self._loop, self._previous = loop, loop.get_exception_handler()
        loop.set_exception_handler(self._handle)

    def uninstall(self) -> None:
        """Put the previous handler back; say how many failures there were. Idempotent."""
        loop, self._loop = self._loop, None
        if loop is not None and loop.get_exception_handler() == self._handle:
            loop.set_exception_handler(self._previous)
        if self.count > 1:
            self.events.emit("warning", "web", f"{self.count} connections could not be accepted in all (out of "
                             "descriptors)")
            self.count = 0

    def _handle(self, loop: asyncio.AbstractEventLoop, context: dict[str, Any]) -> None:
        if str(context.get("message", "")).startswith("socket.accept() out of system resource"):
            self.count += 1
            if self.count == 1:
                exc = context.get("exception")
                why = getattr(exc, "strerror", None) or exc
                self.events.emit("error", "web", f"the page cannot accept connections ({why}): something holds "
                                 "the descriptors the page leaves to itself; it tries again every second (said once)")
            return
        if self._previous is not None:
            self._previous(loop, context)
        else:
            loop.default_exception_handler(context)
