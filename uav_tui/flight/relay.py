"""What the processor's outputs beside the vector share on their way to the autopilot (landing targets, gimbal
setpoints): one send at a time, bounded, counted, a failure said once; and the checks of the moment (link alive,
frame fresh, nothing still being sent) every output passes before it is sent."""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any

from controllers.errors import ControllerError, NotSupported

if TYPE_CHECKING:
    from controllers.base import FlightController
    from uav_tui.config import SafetyConfig
    from uav_tui.events import EventLog

SEND_TIMEOUT_S = 1.0
"""The longest one send may take (a landing target older than a second is stale to ArduPilot)."""


class OneAtATime:
    """Sends one item at a time to the controller, counting what was sent and what failed.

    An item that comes while the previous one is still being sent is skipped by the caller (:attr:`busy`: the newest
    frame wins, as for frames). A failure is said once in the event log until a different one comes; whatever a send
    raises is such a failure (a refusal below the controller's errors too), never an unretrieved task exception. A
    :class:`~controllers.errors.NotSupported` stays true (:attr:`unsupported`): nothing more is sent.

    Args:
        events: the core's event log.
        what: what is sent, for the event log (``landing target``).
        timeout_s: the longest one send may take.
    """

    def __init__(self, events: EventLog, what: str, timeout_s: float = SEND_TIMEOUT_S) -> None:
        self.events = events
        self.what = what
        self.timeout_s = timeout_s
        self.sent = 0
        self.failed = 0
        self.last_error = ""
        self.unsupported = ""
        """Why the controller cannot take these at all (its NotSupported), "" until it said so."""
        self._task: asyncio.Task[None] | None = None

    @property
    def busy(self) -> bool:
        return self._task is not None and not self._task.done()

    def start(self, send: Callable[[], Awaitable[Any]]) -> None:
        """Start ``send()`` on the loop; the caller checked :attr:`busy`."""
        self._task = asyncio.get_running_loop().create_task(self._send(send), name=self.what)

    async def _send(self, send: Callable[[], Awaitable[Any]]) -> None:
        try:
            async with asyncio.timeout(self.timeout_s):
                await send()
        except Exception as exc:  # noqa: BLE001 - each failure counted and said; the loop never sees it
            self.failed += 1
            error = str(exc) or f"no answer within {self.timeout_s:g} s"
            if not isinstance(exc, ControllerError | TimeoutError):
                error = f"{type(exc).__name__}: {error}"
            if isinstance(exc, NotSupported):
                self.unsupported = error
            if error != self.last_error:
                self.events.emit("warning", "autonomy", f"{self.what} not sent: {error}")
            self.last_error = error
        else:
            self.sent += 1
            self.last_error = ""

    async def settle(self) -> None:
        """Wait for the send in progress to end (it is bounded by ``timeout_s``)."""
        if self._task is not None:
            await asyncio.gather(self._task, return_exceptions=True)

    async def close(self) -> None:
        if self._task is not None:
            self._task.cancel()
            await asyncio.gather(self._task, return_exceptions=True)


def not_now(controller: FlightController, safety: SafetyConfig, frame_age_s: float, sender: OneAtATime) -> str:
    """Why an output of a frame ``frame_age_s`` old is not sent now (link lost, frame stale, the previous one still
    being sent), or ""."""
    age = controller.heartbeat_age_s()
    if age >= safety.link_timeout:
        return f"link lost (heartbeat {age:.1f} s old)"
    if frame_age_s >= safety.max_frame_age:
        return f"frame {frame_age_s:.2f} s old"
    if sender.unsupported:
        return sender.unsupported
    if sender.busy:
        return "the previous one is still being sent"
    return ""
