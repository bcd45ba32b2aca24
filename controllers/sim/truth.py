"""Client of the simulator's ground-truth channel (protocol in :mod:`controllers.sim`)."""

from __future__ import annotations

import itertools
import json
import logging
import socket
import threading
import time
from typing import Any

logger = logging.getLogger(__name__)


class TruthClient:
    """Subscribes to a simulator's truth stream and keeps the newest sample.

    A daemon thread reads the socket; ``latest()`` never blocks, ``request()`` blocks at most
    ``timeout`` seconds (call it from a thread, or ``asyncio.to_thread``, inside async code).
    Safe to use from several threads.

    Args:
        port: the simulator's truth port (``SimVehicle.truth_port``).
        host: where the simulator runs (always loopback in practice).
        subscribe: start the 50 Hz stream at once; without it only ``request`` is useful.
    """

    def __init__(self, port: int, host: str = "127.0.0.1", *, subscribe: bool = True) -> None:
        self._addr = (host, port)
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.bind(("127.0.0.1", 0))
        self._sock.settimeout(0.2)
        self._latest: dict[str, Any] | None = None
        self._replies: dict[int, dict[str, Any]] = {}
        self._cond = threading.Condition()
        self._ids = itertools.count(1)
        self._closed = threading.Event()
        self._thread = threading.Thread(target=self._read, name=f"truth-client:{port}", daemon=True)
        self._thread.start()
        if subscribe:
            self._send({"cmd": "subscribe", "id": next(self._ids)})  # an id keeps the answer out of latest()

    def latest(self) -> dict[str, Any] | None:
        """The newest truth datagram received, or None before the first."""
        with self._cond:
            return self._latest

    def wait_latest(self, timeout: float = 2.0) -> dict[str, Any]:
        """The next truth datagram after now (blocks up to ``timeout``).

        Raises:
            TimeoutError: nothing arrived (is the simulator running, did you subscribe?).
        """
        deadline = time.monotonic() + timeout
        with self._cond:
            before = self._latest
            while self._latest is before:
                left = deadline - time.monotonic()
                if left <= 0 or not self._cond.wait(left):
                    raise TimeoutError(f"no truth from simulator at {self._addr} within {timeout} s")
            assert self._latest is not None
            return self._latest

    def request(self, cmd: dict[str, Any], timeout: float = 1.0) -> dict[str, Any]:
        """Send one control request and return the simulator's reply.

        Raises:
            TimeoutError: no reply within ``timeout`` seconds (the request is sent once more halfway).
        """
        req_id = next(self._ids)
        payload = {**cmd, "id": req_id}
        deadline = time.monotonic() + timeout
        resent = False
        self._send(payload)
        with self._cond:
            while req_id not in self._replies:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise TimeoutError(f"simulator at {self._addr} did not answer {cmd.get('cmd')!r}")
                if not resent and left < timeout / 2:
                    resent = True
                    self._send(payload)
                self._cond.wait(min(left, timeout / 2))
            return self._replies.pop(req_id)

    def close(self) -> None:
        """Unsubscribe and stop the reader thread; idempotent."""
        if self._closed.is_set():
            return
        self._send({"cmd": "unsubscribe", "id": next(self._ids)})
        self._closed.set()
        self._thread.join(timeout=1.0)
        self._sock.close()

    def __enter__(self) -> TruthClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _send(self, payload: dict[str, Any]) -> None:
        try:
            self._sock.sendto(json.dumps(payload).encode(), self._addr)
        except OSError as exc:
            logger.debug("TruthClient(%s) send failed: %s", self._addr, exc)

    def _read(self) -> None:
        while not self._closed.is_set():
            try:
                data, _ = self._sock.recvfrom(65535)
                msg = json.loads(data)
            except (TimeoutError, OSError, ValueError):
                continue
            if not isinstance(msg, dict):
                continue
            with self._cond:
                if "ok" not in msg:
                    self._latest = msg
                elif "id" in msg:
                    self._replies[msg["id"]] = msg
                    if len(self._replies) > 64:
                        self._replies.pop(next(iter(self._replies)))
                self._cond.notify_all()
