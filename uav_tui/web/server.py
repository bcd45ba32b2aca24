"""The side page: aiohttp routes, token check, WebRTC signalling, status push and page commands.

Routes (every one needs the token or the page's session, else 401 and nothing else):

- ``GET /?token=T``: the page (it also sets an HttpOnly session cookie, so ``/static/*`` loads);
- ``POST /offer``: the browser's SDP offer -> the answer with the processed video track;
- ``GET /ws?token=T``: a websocket the server pushes status (twice a second) and events into;
- ``POST /api/roi``: ``{"rect": [x0, y0, x1, y1]}`` or ``{"point": [x, y]}``, normalized -> ``roi`` (a point inside
  a track's box: ``lock ID``);
- ``POST /api/command``: ``{"command": "f 2"}``, one of WEB_COMMANDS.

Every field of a request is checked before use; a handler that still raises (a bug) answers that request
with a 500 and is reported once (:class:`HandlerFailures`), and the server goes on.

Access (the token, the page's session, the throttle, the origins) is :class:`~uav_tui.web.access.AccessGuard`'s;
how many connections are taken and for how long, :mod:`uav_tui.web.connections`'s; the video's peer connections,
:class:`~uav_tui.web.viewers.Viewers`'. Commands go through ``core.execute(..., origin="web:<ip>")``, the one
command module.
"""

from __future__ import annotations

import asyncio
import json
import logging
import math
import secrets
import socket
import time
from pathlib import Path
from typing import Any

from aiohttp import WSCloseCode, web

from uav_tui.config import WebConfig
from uav_tui.errors import KNOWN_ERRORS, CommandError, UavError
from uav_tui.events import Event
from uav_tui.flight.commands import Command, parse
from uav_tui.output.line_budget import LineBudget
from uav_tui.output.text import describe
from uav_tui.status import CoreState
from uav_tui.web.access import AccessGuard
from uav_tui.web.connections import (
    BACKLOG,
    BODY_TIMEOUT_S,
    IDLE_TIMEOUT_S,
    AcceptFailures,
    ConnectionLimits,
    LimitedServer,
    connection_budget,
)
from uav_tui.web.failures import HandlerFailures
from uav_tui.web.mdns import adopt_mdns_resolver
from uav_tui.web.roi import lock_or_roi, roi_from_message
from uav_tui.web.tracks import VideoHub
from uav_tui.web.view import ServedCore
from uav_tui.web.viewers import Viewers, ViewersFull

logger = logging.getLogger(__name__)

STATIC = Path(__file__).with_name("static")
STATUS_PERIOD_S = 0.5
WEB_COMMANDS = frozenset({"f", "roi", "unlock", "hold", "land", "precland", "rtl", "autonomy off"})
"""What the page may send: the buttons, target selection, the ways to stop and to land. Arming, takeoff and
switching autonomy on stay with the operator's terminal."""


class WebServer:
    """Serves the page for one running core.

    Args:
        core: the running core (:class:`~uav_tui.web.view.ServedCore`).
        config: the ``[web]`` section.
    """

    def __init__(self, core: ServedCore, config: WebConfig) -> None:
        self.core = core
        self.config = config
        self.token = config.web_token or secrets.token_urlsafe(24)  # 192 bits (config refuses under 96)
        self.video = VideoHub(core, config.web_width, config.web_fps)
        self.port = config.web_port
        self.viewers = Viewers(self.video, core.events)
        self._sockets: set[web.WebSocketResponse] = set()
        self._queues: set[asyncio.Queue[dict[str, Any]]] = set()
        self.limits = ConnectionLimits(connection_budget(), core.events)
        self.access = AccessGuard(self.token, config.web_origins, core.events, self.limits)
        self._accept_failures = AcceptFailures(core.events)
        self._app_runner: web.AppRunner | None = None
        self._runner: web.ServerRunner | None = None
        self.failures = HandlerFailures(core.events, "web page")
        self._refusals: LineBudget[tuple[str, str]] | None = None
        """Events for bad requests (made on the loop, at the first one)."""

    @property
    def url(self) -> str:
        """The page's address with the token, for the operator to open."""
        host = self.config.web_host
        if host in ("", "0.0.0.0", "::"):
            host = _reachable_address()
        return f"http://{host}:{self.port}/?token={self.token}"

    async def start(self) -> None:
        adopt_mdns_resolver()
        app = web.Application(middlewares=[self._guard, self.access.middleware], client_max_size=256 * 1024)
        app.router.add_get("/", self._page)
        app.router.add_static("/static/", STATIC)
        app.router.add_post("/offer", self._offer)
        app.router.add_get("/ws", self._websocket)
        app.router.add_post("/api/roi", self._roi)
        app.router.add_post("/api/command", self._command)
        self._app_runner = web.AppRunner(app)  # the application's startup and cleanup
        await self._app_runner.setup()
        assert self._app_runner.server is not None
        # The connections are this server's: it takes only those the limits allow, and aiohttp closes them when
        # idle (also before a first request: a client that sends nothing or a byte at a time).
        server = LimitedServer(self._app_runner.server.request_handler, limits=self.limits,
                               request_factory=self._app_runner.server.request_factory,
                               keepalive_timeout=IDLE_TIMEOUT_S, access_log=None)
        self._runner = web.ServerRunner(server)
        await self._runner.setup()
        site = web.TCPSite(self._runner, self.config.web_host, self.config.web_port, backlog=BACKLOG)
        try:
            await site.start()
        except OSError as exc:
            await self.stop()
            raise UavError(f"web page: cannot listen on {self.config.web_host}:{self.config.web_port} "
                           f"({exc.strerror}); pick another --web-port") from exc
        self._accept_failures.install(asyncio.get_running_loop())
        self.core.events.add_listener(self._on_event)

    async def stop(self) -> None:
        """Close every viewer and the listening socket. Idempotent."""
        self.core.events.remove_listener(self._on_event)
        if self._runner is not None:
            runner, self._runner = self._runner, None
            await self._close_viewers()
            await runner.cleanup()
        if self._app_runner is not None:
            app_runner, self._app_runner = self._app_runner, None
            await app_runner.cleanup()
        self._accept_failures.uninstall()
        self.failures.close()
        if self._refusals is not None:
            self._refusals.close()

    # -- access ----------------------------------------------------------------------------------

    @web.middleware
    async def _guard(self, request: web.Request, handler: Any) -> web.StreamResponse:
        """A handler that raises (a bug) fails its own request with a 500, reported; the server goes on."""
        try:
            return await handler(request)
        except web.HTTPException:
            raise
        except Exception as exc:  # noqa: BLE001 - reported once by HandlerFailures
            self.failures.failed(f"{request.method} {describe(request.path)} from {_origin(request)}", exc)
            raise web.HTTPInternalServerError(text="500: this request could not be handled (a bug, logged); "
                                                   "the page goes on") from None

    async def _page(self, request: web.Request) -> web.StreamResponse:
        response = web.FileResponse(STATIC / "index.html")
        self.access.admit(response)
        return response

    # -- video -----------------------------------------------------------------------------------

    async def _offer(self, request: web.Request) -> web.Response:
        origin = _origin(request)
        body = await self._json(request, origin, "offer")
        if not (isinstance(body.get("sdp"), str) and body.get("type") == "offer"):
            raise self._bad_request(origin, "offer must be JSON {\"sdp\": ..., \"type\": \"offer\"}")
        try:
            answer = await self.viewers.answer(body["sdp"], origin)
        except ViewersFull as exc:
            raise web.HTTPServiceUnavailable(text=str(exc)) from None
        except ValueError as exc:
            raise self._bad_request(origin, str(exc)) from None
        return web.json_response({"sdp": answer.sdp, "type": answer.type})

    # -- status push -----------------------------------------------------------------------------

    async def _websocket(self, request: web.Request) -> web.WebSocketResponse:
        ws = web.WebSocketResponse(heartbeat=20)
        await ws.prepare(request)
        queue: asyncio.Queue[dict[str, Any]] = asyncio.Queue(maxsize=100)
        self._sockets.add(ws)
        self._queues.add(queue)
        sender = asyncio.create_task(self._push(ws, queue))
        try:
            async for _ in ws:  # the page sends nothing here; commands are POSTed
                pass
        finally:
            self._queues.discard(queue)
            self._sockets.discard(ws)
            sender.cancel()
            await asyncio.gather(sender, return_exceptions=True)
        return ws

    async def _push(self, ws: web.WebSocketResponse, queue: asyncio.Queue[dict[str, Any]]) -> None:
        for event in list(self.core.events.recent)[-8:]:
            await ws.send_str(_dumps(_event_message(event)))
        while not ws.closed:
            await ws.send_str(_dumps(self._status_message()))
            deadline = time.monotonic() + STATUS_PERIOD_S
            while (left := deadline - time.monotonic()) > 0:
                try:
                    message = await asyncio.wait_for(queue.get(), left)
                except TimeoutError:
                    break
                await ws.send_str(_dumps(message))

    def _status_message(self) -> dict[str, Any]:
        source = self.core.source
        width, height = source.get_frame_size() if source is not None else (0, 0)
        status = self.core.status().as_dict() if self.core.state is CoreState.RUNNING else {}
        return {"type": "status", "status": status, "frame": [width, height], "viewers": self.video.viewers}

    def _on_event(self, event: Event) -> None:
        message = _event_message(event)
        for queue in tuple(self._queues):
            if not queue.full():  # a stalled viewer misses events, it never holds up the loop
                queue.put_nowait(message)

    # -- commands --------------------------------------------------------------------------------

    async def _roi(self, request: web.Request) -> web.Response:
        origin = _origin(request)
        body = await self._json(request, origin, "roi")
        source = self.core.source
        size = source.get_frame_size() if source else (0, 0)
        try:
            roi = roi_from_message(body, size)
        except CommandError as exc:
            raise self._bad_request(origin, f"roi rejected: {exc}") from None
        point = body.get("point") if body.get("rect") is None else None  # a click, checked as the roi's
        return await self._run(lock_or_roi(roi, point, size, self.core.lock), origin)

    async def _command(self, request: web.Request) -> web.Response:
        origin = _origin(request)
        body = await self._json(request, origin, "command")
        text = body.get("command")
        try:
            command = parse(text) if isinstance(text, str) else None
        except CommandError as exc:
            raise self._bad_request(origin, f"command rejected: {exc}") from None
        if command is None or not ({command.word, str(command)} & WEB_COMMANDS):
            raise self._bad_request(origin, f"command {describe(text)} is not allowed from the page; allowed: "
                              f"{', '.join(sorted(WEB_COMMANDS))}")
        return await self._run(command, origin)

    async def _run(self, command: Command, origin: str) -> web.Response:
        try:
            message = await self.core.execute(command, origin=origin)
        except KNOWN_ERRORS as exc:  # already logged as an event by the core
            return web.json_response({"ok": False, "message": str(exc)}, status=409)
        return web.json_response({"ok": True, "message": message or str(command)})

    async def _json(self, request: web.Request, origin: str, what: str) -> dict[str, Any]:
        try:
            async with asyncio.timeout(BODY_TIMEOUT_S):
                body = await request.json()
        except TimeoutError:
            raise web.HTTPRequestTimeout(text=f"408: the body did not arrive within {BODY_TIMEOUT_S:g} s") from None
        except (ValueError, RecursionError):  # not JSON, not UTF-8, or nested too deep to parse
            body = None
        if not isinstance(body, dict):
            raise self._bad_request(origin, f"{what}: the body is not a JSON object")
        return body

    def _bad_request(self, origin: str, message: str) -> web.HTTPBadRequest:
        """Log a refused request as an event (within a line budget: a flood is counted) and return the 400 to
        raise; nothing else changes."""
        if self._refusals is None:
            self._refusals = LineBudget(lambda said: self.core.events.emit("warning", "web", *said),
                                        lambda count: self.core.events.emit(
                                            "warning", "web", f"{count} more bad requests refused"))
        self._refusals.line((message, origin))
        return web.HTTPBadRequest(text=message)

    async def _close_viewers(self) -> None:
        """Close the websockets and every peer connection (before the server closes the connections)."""
        for ws in tuple(self._sockets):
            await ws.close(code=WSCloseCode.GOING_AWAY, message=b"uav-tui is stopping")
        await self.viewers.close()


def _origin(request: web.Request) -> str:
    return f"web:{request.remote or '?'}"


def _event_message(event: Event) -> dict[str, Any]:
    return {"type": "event", "t_wall_ns": event.t_wall_ns, "level": event.level, "kind": event.kind,
            "message": event.message, "origin": event.origin}


def _dumps(message: dict[str, Any]) -> str:
    return json.dumps(_finite(message), default=str)


def _finite(value: Any) -> Any:
    """JSON has no NaN/inf (browsers refuse them): replace them with null."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    return value


def _reachable_address() -> str:
    """This machine's address on the default route (no packet is sent), else its host name."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(("192.0.2.1", 9))
            return probe.getsockname()[0]
        except OSError:
            return socket.gethostname()
