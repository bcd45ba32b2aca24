"""Who may use the page: the token, the page's session, the throttle on guessing, and the origins allowed.

A request is let in with a session cookie the page was given (:data:`COOKIE`: a random value made when the page
was opened with the token, never the token itself), or with the right token (``?token=`` or
``Authorization: Bearer``) from an address the throttle (:class:`~uav_tui.web.throttle.AuthThrottle`) does not
block. An open page (it holds its session) is so never locked out by someone else's guesses from its address.

POST routes and the websocket also refuse a browser ``Origin`` that is not this page's: the address and port the
request reached (the listening socket's own, never the request's ``Host`` header, which a DNS-rebinding page sets
to its own name), ``localhost`` on loopback, this machine's host name (and ``.local``), or one listed in
``web_origins``.
"""

from __future__ import annotations

import math
import secrets
import socket
import time
from collections import OrderedDict
from collections.abc import Awaitable, Callable

from aiohttp import web

from uav_tui.events import EventLog
from uav_tui.output.text import describe
from uav_tui.web.connections import ConnectionLimits
from uav_tui.web.throttle import AuthThrottle

COOKIE = "uav_session"
MAX_SESSIONS = 64
"""Sessions remembered (the oldest is forgotten first): each opening of the page makes one."""
_REJECT_LOG_PERIOD_S = 60.0

Handler = Callable[[web.Request], Awaitable[web.StreamResponse]]


class AccessGuard:
    """The page's middleware for access (:meth:`middleware`) and the session given with the page (:meth:`admit`).

    Args:
        token: the page's token.
        origins: the ``web_origins`` setting (comma-separated).
        events: where refused requests are said (one per address a minute).
        limits: told which addresses showed the token (the operator's: they keep connections).
    """

    def __init__(self, token: str, origins: str, events: EventLog, limits: ConnectionLimits) -> None:
        self.token = token
        self.events = events
        self.limits = limits
        self.throttle = AuthThrottle()
        self._origins = frozenset(o.strip().rstrip("/").lower() for o in origins.split(",") if o.strip())
        self._sessions: OrderedDict[str, None] = OrderedDict()
        self._rejected: dict[str, float] = {}

    def admit(self, response: web.StreamResponse) -> None:
        """Give ``response`` (the page) a new session cookie."""
        session = secrets.token_urlsafe(24)
        self._sessions[session] = None
        while len(self._sessions) > MAX_SESSIONS:
            self._sessions.popitem(last=False)
        response.set_cookie(COOKIE, session, httponly=True, samesite="Strict")

    @web.middleware
    async def middleware(self, request: web.Request, handler: Handler) -> web.StreamResponse:
        address = request.remote or "?"
        if request.cookies.get(COOKIE, "") not in self._sessions:
            self._check_token(request, address)
        self.limits.trust(address)
        if (request.method == "POST" or request.path == "/ws") and not self._origin_allowed(request):
            self._note_rejected(request, f"origin {describe(request.headers['Origin'])} not allowed")
            raise web.HTTPForbidden(text="403: requests from another site's page are refused; add its origin to "
                                         "web_origins to allow it")
        return await handler(request)

    def _check_token(self, request: web.Request, address: str) -> None:
        wait = self.throttle.retry_after(address)
        if wait > 0:
            self._note_rejected(request, "too many failed attempts")
            seconds = math.ceil(wait)
            raise web.HTTPTooManyRequests(text=f"429: too many failed attempts; retry in {seconds} s",
                                          headers={"Retry-After": str(seconds)})
        given = request.query.get("token", "")
        header = request.headers.get("Authorization", "")
        if header.startswith("Bearer "):
            given = header[len("Bearer "):]
        if not secrets.compare_digest(given.encode(), self.token.encode()):
            self.throttle.failed(address)
            self._note_rejected(request, "no valid token")
            raise web.HTTPUnauthorized(text="401: a valid token is required")
        self.throttle.succeeded(address)

    def _origin_allowed(self, request: web.Request) -> bool:
        """No ``Origin`` (not a browser), this page's own (:func:`own_origins`), or one in ``web_origins``."""
        origin = request.headers.get("Origin")
        if origin is None:
            return True
        origin = origin.rstrip("/").lower()
        return origin in self._origins or origin in own_origins(request)

    def _note_rejected(self, request: web.Request, why: str) -> None:
        """An event for a refused request, at most one per client address a minute."""
        ip = request.remote or "?"
        now = time.monotonic()
        if now - self._rejected.get(ip, -math.inf) > _REJECT_LOG_PERIOD_S:
            if len(self._rejected) > 4096:
                self._rejected.clear()
            self._rejected[ip] = now
            self.events.emit("warning", "web", f"refused {request.method} {describe(request.path)}: {why}",
                             f"web:{ip}")


def own_origins(request: web.Request) -> frozenset[str]:
    """The origins of this page as a browser names it: the address and port the request reached, ``localhost``
    when that is loopback, and this machine's host name (and ``.local``) at that port."""
    sockname = request.transport.get_extra_info("sockname") if request.transport is not None else None
    if not (isinstance(sockname, tuple) and len(sockname) >= 2):
        return frozenset()
    address, port = str(sockname[0]), int(sockname[1])
    hosts = {f"[{address}]" if ":" in address else address}
    if address.startswith("127.") or address == "::1":
        hosts |= {"localhost", "127.0.0.1", "[::1]"}
    name = socket.gethostname().lower()
    hosts |= {name, f"{name}.local"}
    suffix = "" if port == 80 else f":{port}"
    return frozenset(f"http://{host}{suffix}" for host in hosts)
