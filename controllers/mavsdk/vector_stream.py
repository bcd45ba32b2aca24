"""Stream a body-frame velocity setpoint for t seconds, then zero and hold (safety rule 3).

Every setpoint is sent from here (MAVSDK's Offboard plugin, which re-sends the last setpoint from
its own thread, is not used), every vector ends explicitly (zero velocity, then a holding mode), a
new vector replaces a running one without leaving offboard, and a vehicle that leaves offboard by
itself (RC takeover, failsafe) is left alone.
"""

from __future__ import annotations

import asyncio
import logging
import time
from typing import Protocol

from controllers.errors import ControllerError
from controllers.vector_end import VectorEnd, VectorEndKind

logger = logging.getLogger(__name__)

DEFAULT_RATE_HZ = 20.0
"""Setpoint rate, the one docs/safety.md promises; PX4 wants >= 2 Hz, ArduCopter a target within GUID_TIMEOUT."""

PRESTREAM_S = 0.1
"""PX4 accepts offboard only while setpoints are already streaming; stream this long before asking."""

_STOPPED = VectorEnd(VectorEndKind.STOPPED)
"""A vector cut short by a command or a stop."""

_REFUSED = VectorEnd(VectorEndKind.FAILED, "offboard refused")
"""A vector whose start_offboard failed (or was cancelled)."""


class OffboardPort(Protocol):
    """What a VectorStream needs from the autopilot side (:class:`~controllers.mavsdk.offboard.MavsdkOffboard`)."""

    async def send_velocity_body(self, forward_ms: float, right_ms: float) -> None:
        """Send one body-frame velocity setpoint (altitude and yaw held)."""
        ...

    async def start_offboard(self, *, yield_to_others: bool = False) -> None:
        """Switch to the velocity-control mode (PX4 OFFBOARD, ArduCopter GUIDED); with ``yield_to_others``, not from a
        mode someone else chose (raises ControllerError)."""
        ...

    async def stop_offboard(self) -> None:
        """Leave velocity control into a hold that ignores the sticks (PX4 HOLD, ArduCopter GUIDED at zero)."""
        ...

    def flight_mode_since(self, t_mono: float) -> str | None:
        """The flight mode telemetry last reported (``"OFFBOARD"``, ``"HOLD"``...) if it arrived after
        ``t_mono`` (time.monotonic()), else None: an older report may predate our own mode change."""
        ...


class VectorStream:
    """One vector at a time: start (or replace), stream at ``rate_hz``, then zero and hold.

    Args:
        port: the autopilot side.
        rate_hz: setpoint rate while a vector runs.
        name: used in log lines.
    """

    def __init__(self, port: OffboardPort, *, rate_hz: float = DEFAULT_RATE_HZ, name: str = "vector") -> None:
        self._port = port
        self._period_s = 1.0 / rate_hz
        self._name = name
        self._lock = asyncio.Lock()
        self._task: asyncio.Task[None] | None = None
        self._target = (0.0, 0.0)
        self._deadline = 0.0
        self.engaged = False
        """True from a successful start_offboard until the vehicle was put back into a holding mode."""
        self.setpoints_sent = 0
        """Setpoints sent since construction (diagnostics)."""
        self._seen_offboard = False
        self._engaged_at = 0.0
        self.last_end = VectorEnd()
        """How the last vector ended (none yet, completed, stopped, failed, left offboard)."""

    @property
    def active(self) -> bool:
        """True while a vector's setpoints are being streamed, and until its end (zero, then the hold) is out."""
        return self._task is not None and not self._task.done()

    async def start(self, vx: float, vy: float, t: float, *, yield_to_others: bool = False) -> None:
        """Run (vx, vy) for t seconds; replaces a running vector without leaving offboard.

        Returns once the first setpoint is sent and offboard is engaged. ``yield_to_others`` (autonomy's vectors):
        a mode someone else chose meanwhile (a pilot, a failsafe) wins, see ``OffboardPort.start_offboard``.

        Raises:
            ControllerError: offboard could not be started (the stream is stopped again).
        """
        async with self._lock:
            self._target = (vx, vy)
            self._deadline = time.monotonic() + t
            await self._send(vx, vy)
            if self.active:
                return
            self._task = asyncio.create_task(self._stream(), name=f"{self._name}-stream")
            if not self.engaged:
                try:
                    await asyncio.sleep(PRESTREAM_S)
                    await self._port.start_offboard(yield_to_others=yield_to_others)
                except BaseException:
                    await self._cancel_task()
                    raise
                self.engaged = True
                self._seen_offboard = False
                self._engaged_at = time.monotonic()

    async def cancel(self) -> bool:
        """Stop streaming at once without changing the mode; returns whether offboard is still engaged.

        Used when an operator command pre-empts the vector: the caller sends the vehicle elsewhere.
        """
        async with self._lock:
            await self._cancel_task(_STOPPED)
            return self.engaged

    async def stop_and_hold(self) -> None:
        """Stop streaming, send zero velocity, and leave offboard into a holding mode (if engaged)."""
        async with self._lock:
            await self._cancel_task(_STOPPED)
            await self._zero_and_hold()

    async def _cancel_task(self, why: VectorEnd = _REFUSED) -> None:
        task, self._task = self._task, None
        if task is not None and task is not asyncio.current_task():
            task.cancel()
            await asyncio.gather(task, return_exceptions=True)
            self.last_end = why

    async def _send(self, vx: float, vy: float) -> None:
        await self._port.send_velocity_body(vx, vy)
        self.setpoints_sent += 1

    async def _zero_and_hold(self) -> None:
        if not self.engaged:
            return
        await self._send(0.0, 0.0)
        await self._port.stop_offboard()
        self.engaged = False

    async def _stream(self) -> None:
        next_at = time.monotonic()
        try:
            while True:
                now = time.monotonic()
                next_at = max(next_at + self._period_s, now)  # after a stall: no burst of late ticks
                if now >= self._deadline:
                    async with self._lock:
                        if time.monotonic() < self._deadline:
                            continue  # replaced while we waited for the lock
                        self.last_end = VectorEnd(VectorEndKind.COMPLETED)
                        await self._zero_and_hold()
                        self._task = None  # active until the hold is out: a caller's next step must not race it
                        return
                await asyncio.sleep(max(0.0, min(next_at, self._deadline) - now))
                if self._vehicle_left_offboard():
                    return
                if time.monotonic() < self._deadline:
                    await self._send(*self._target)
        except ControllerError as exc:
            logger.error("%s: streaming failed (%s); trying to hold", self._name, exc)
            self.last_end = VectorEnd(VectorEndKind.FAILED, str(exc))
            try:
                await self._port.stop_offboard()
                self.engaged = False
            except ControllerError as hold_exc:
                logger.error("%s: hold after a failed stream failed too: %s", self._name, hold_exc)
            self._task = None

    def _vehicle_left_offboard(self) -> bool:
        """True (and the vector abandoned, no hold sent) once the vehicle was seen leaving offboard.

        Someone else changed the mode: the RC pilot taking over, a failsafe, a ground station. A hold
        at the end of the vector would take the vehicle back from them.
        """
        mode = self._port.flight_mode_since(self._engaged_at)
        if mode == "OFFBOARD":
            self._seen_offboard = True
        elif self._seen_offboard and mode is not None and self.engaged:
            logger.warning(
                "%s: the vehicle left offboard (now %s); vector abandoned, mode left alone", self._name, mode
            )
            self._task = None
            self.engaged = False
            self.last_end = VectorEnd(VectorEndKind.LEFT_OFFBOARD, mode)
            return True
        return False
