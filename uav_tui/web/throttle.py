"""Slows token guessing per client address, without ever locking the operator out for longer than ``max_delay_s``."""

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
    streak_from: float = 0.0
    """When the blocks in a row (each failure within ``open_s`` of the last block's end) began."""


class AuthThrottle:
    """Counts failed token checks per client address and says how long to refuse it.

    The first ``free`` failures cost nothing (a mistyped token). Each further failure blocks the
    address for ``base_s`` seconds, doubling per failure; while blocked, every request from it is refused
    unchecked (a guess during the block teaches nothing). Blocks in a row never add up to more than
    ``max_delay_s``: someone who guesses without pause from the operator's address (the same NAT, loopback
    through a tunnel) would otherwise renew the block the moment it ends, for good. After ``max_delay_s``
    blocked in a row the address gets ``open_s`` seconds in which every request is checked (the operator,
    retrying after ``Retry-After``, gets in), then the blocks start again. Failures are forgotten
    ``forget_s`` after the last one, and a request with the right token clears them. At most
    ``max_clients`` addresses are remembered (the oldest is forgotten first).

    Args:
        clock: monotonic seconds (tests pass their own).
    """

    def __init__(self, *, free: int = 5, base_s: float = 1.0, max_delay_s: float = 30.0, open_s: float = 2.0,
                 forget_s: float = 300.0, max_clients: int = 4096, clock: Callable[[], float] = time.monotonic) -> None:
        self.free, self.base_s, self.max_delay_s, self.open_s = free, base_s, max_delay_s, open_s
        self.forget_s = forget_s
        self.max_clients = max_clients
        self.clock = clock
        self._clients: OrderedDict[str, _Client] = OrderedDict()

    def retry_after(self, address: str) -> float:
        """Seconds ``address`` must still wait before its next attempt is checked (0: check it now)."""
        client = self._clients.get(address)
        return max(0.0, client.blocked_until - self.clock()) if client is not None else 0.0

    def failed(self, address: str) -> float:
        """Count a failed attempt; returns how long ``address`` is now blocked (0 while free or open)."""
        now = self.clock()
        client = self._clients.pop(address, None) or _Client()
        if now - client.last_failure > self.forget_s:
            client.failures = 0
        client.failures += 1
        client.last_failure = now
        self._clients[address] = client
        while len(self._clients) > self.max_clients:
            self._clients.popitem(last=False)
        over = client.failures - self.free
        if over <= 0:
            return 0.0
        if client.blocked_until == 0.0 or now - client.blocked_until > self.open_s:
            client.streak_from = now  # a first block, or the address was open for open_s: a new run of blocks
        left = self.max_delay_s - (now - client.streak_from)
        if left <= 0:  # blocked for max_delay_s in a row: the open window (checked, not blocked)
            return 0.0
        delay = min(left, self.base_s * 2.0 ** min(over - 1, 64))
        client.blocked_until = now + delay
        return delay

    def succeeded(self, address: str) -> None:
        """The right token: forget this address's failures."""
        self._clients.pop(address, None)
