"""The contract every output relay keeps: the core builds one per registry entry and calls it on each frame."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from uav_tui.hosting.host import ProcessedFrame


class OutputRelay(Protocol):
    """Turns one processor output (``field`` of the frame's outputs) into an effect, gated and counted."""

    field: str
    """The output it relays (``gimbal``)."""

    def consider(self, result: ProcessedFrame) -> None:
        """Act on ``result``'s output now (on the loop, never blocking) and say on ``result`` what was done."""

    def stop(self, reason: str) -> None:
        """Autonomy stopped for ``reason``: end any effect under way."""

    async def close(self) -> None:
        """The platform exits: wait for what is under way (before the controller closes)."""

    @property
    def counts(self) -> Mapping[str, int]:
        """What it did so far (``sent``, ``failed``)."""
