"""Slows token guessing per client address, without locking the operator out for long."""

from __future__ import annotations

import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass


@dataclass(slots=True)
class _Client:
    failures: int = 0
    last_failure: float = 0.0
    blocked_until: float = 0.0


class AuthThrottle:
    """Counts failed token checks per client address and says how long to refuse it.

    The first ``free`` failures cost nothing (a mistyped token). Each further failure blocks the
    address for ``base_s`` seconds, doubling per failure up to ``max_delay_s``; while blocked, every
    request from it is refused unchecked (a guess during the block teaches nothing). Failures are
    forgotten ``forget_s`` after the last one, and a request with the right token clears them.
    At most ``max_clients`` addresses are remembered (the oldest is forgotten first).

    Args:
        clock: monotonic seconds (tests pass their own).
    """

    def __init__(self, *, free: int = 5, base_s: float = 1.0, max_delay_s: float = 30.0, forget_s: float = 300.0,
                 max_clients: int = 4096, clock: Callable[[], float] = time.monotonic) -> None:
        self.free, self.base_s, self.max_delay_s, self.forget_s = free, base_s, max_delay_s, forget_s
        self.max_clients = max_clients
        self.clock = clock
        self._clients: OrderedDict[str, _Client] = OrderedDict()

    def retry_after(self, address: str) -> float:
        """Seconds ``address`` must still wait before its next attempt is checked (0: check it now)."""
        client = self._clients.get(address)
        return max(0.0, client.blocked_until - self.clock()) if client is not None else 0.0

    def failed(self, address: str) -> float:
        """Count a failed attempt; returns how long ``address`` is now blocked (0 while still free)."""
        now = self.clock()
        client = self._clients.pop(address, None) or _Client()
        if now - client.last_failure > self.forget_s:
            client.failures = 0
        client.failures += 1
        client.last_failure = now
        over = client.failures - self.free
        delay = min(self.max_delay_s, self.base_s * 2.0 ** min(over - 1, 64)) if over > 0 else 0.0
        client.blocked_until = now + delay
        self._clients[address] = client
        while len(self._clients) > self.max_clients:
            self._clients.popitem(last=False)
        return delay

    def succeeded(self, address: str) -> None:
        """The right token: forget this address's failures."""
        self._clients.pop(address, None)
