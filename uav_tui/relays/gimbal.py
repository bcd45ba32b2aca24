"""The processor's gimbal pointing on its way to the autopilot, with the same gate as vectors.

A frame's :class:`~uav_values.gimbal.GimbalPointing` is sent (the controller takes control of the gimbal on the
first, then streams setpoints) only while the operator has autonomy on, the link is alive and the frame is fresh;
the vehicle does not have to fly (a gimbal follows a target while the vehicle holds). Whenever autonomy stops (an
operator command such as ``land`` or ``hold``, a processor fault, the watchdog, the platform's exit) the gimbal is
stopped and control released. A processor that stops returning a pointing stops a gimbal it had turning at a rate.
Each pointing is checked again against the contract's ranges before it is sent (:func:`.judge_gimbal`: the processor
may have changed it after building it); a run of :data:`~uav_tui.flight.plausibility.REFUSALS_TO_STOP` refusals
stops and releases the gimbal until autonomy is next turned on. What was done is each frame's ``gimbal``
(frames.csv): ``sent``, ``refused: why`` or ``not sent: why`` (a vehicle without a gimbal: every frame once it
said so).
"""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING, cast

from controllers.base import GimbalControl
from controllers.errors import ControllerError
from uav_tui.flight.plausibility import RefusalRun, judge_gimbal
from uav_tui.flight.relay import OneAtATime, not_now
from uav_values.gimbal import RATE, GimbalPointing

if TYPE_CHECKING:
    from controllers.base import FlightController
    from uav_tui.config import SafetyConfig
    from uav_tui.events import EventLog
    from uav_tui.flight.autonomy import AutonomyGate
    from uav_tui.hosting.host import ProcessedFrame

RELEASE_TIMEOUT_S = 2.0
"""The longest stopping and releasing the gimbal may take."""

SEND_TIMEOUT_S = 3.0
"""The longest one setpoint may take; the first also waits for MAVSDK to find the gimbal and takes control (a
command acknowledged), later ones are streamed (no answer)."""

STOP = GimbalPointing.rates(0.0, 0.0)


class GimbalRelay:
    """Sends each frame's gimbal pointing while the gate allows it; stops and releases the gimbal when it stops (the
    ``gimbal`` :class:`~uav_tui.relays.contract.OutputRelay`).

    Args:
        controller: the flight controller; a :class:`~controllers.base.GimbalControl`, else TypeError.
        gate: the autonomy gate (its switch and clock; :meth:`stop` is added to its stop listeners).
        safety: link timeout and frame age limits.
        events: the core's event log.
    """

    def __init__(self, controller: FlightController, gate: AutonomyGate, safety: SafetyConfig,
                 events: EventLog) -> None:
        if not isinstance(controller, GimbalControl):
            raise TypeError(f"{controller.description} has no gimbal control")
        self.controller: GimbalControl = controller
        self.field = "gimbal"
        self.gate = gate
        self.safety = safety
        self.events = events
        self.sender = OneAtATime(events, "gimbal setpoint", SEND_TIMEOUT_S)
        self.turning = False
        """The last setpoint sent was a non-zero rate: the gimbal turns until told otherwise."""
        self.releases = 0
        """Times the gimbal was stopped and released."""
        self.refusals = RefusalRun()
        """Pointings that broke the contract's ranges: how many, the last reason, how many in a row."""
        self.halted = ""
        """Why a run of refusals stopped the gimbal ("" while it is not stopped; cleared when autonomy stops)."""
        self._release: asyncio.Task[None] | None = None
        self._epoch = 0
        """Counts stops: a send begun before a stop is dropped after it."""
        gate.stop_listeners.append(self.stop)

    def consider(self, result: ProcessedFrame) -> str:
        """Send ``result``'s pointing if the gate allows it now; returns what was done ("" without a pointing, the
        gimbal left as it was)."""
        given = result.outcome.outputs.gimbal
        if given is None:
            if self.turning and not self._blocked(result):
                self._send(STOP)
                return "stopped (no pointing)"
            return ""
        pointing = judge_gimbal(given)
        if isinstance(pointing, str):
            if self.refusals.refuse(pointing) and not self.halted and self.gate.enabled:
                self.halted = f"{self.refusals.in_a_row} gimbal pointings in a row refused, the last: {pointing}"
                self.events.emit("warning", "autonomy", f"gimbal output stopped: {self.halted}")
                self._halt(self.halted)
            return f"refused: {pointing}"
        self.refusals.accept()
        if why := self._blocked(result):
            return f"not sent: {why}"
        self._send(pointing)
        return "sent"

    def _blocked(self, result: ProcessedFrame) -> str:
        if not self.gate.enabled:
            return "autonomy off"
        if self.halted:
            return f"stopped until autonomy is next turned on ({self.halted})"
        if self._release is not None and not self._release.done():
            return "the gimbal is being released"
        age_s = (self.gate.clock() - result.frame.t_mono_ns) / 1e9
        return not_now(cast("FlightController", self.controller), self.safety, age_s, self.sender)

    def _send(self, pointing: GimbalPointing) -> None:
        epoch = self._epoch
        self.turning = pointing.mode == RATE and (pointing.pitch, pointing.yaw) != (0.0, 0.0)

        async def send() -> None:
            if epoch == self._epoch:  # no stop since the frame was judged
                await self.controller.point_gimbal(pointing.mode, pointing.pitch, pointing.yaw)

        self.sender.start(send)

    def stop(self, reason: str) -> None:
        """Autonomy stopped for ``reason``: stop the gimbal and release control (in a task; :meth:`close` waits)."""
        self.halted = ""
        self._halt(reason)

    def _halt(self, reason: str) -> None:
        """Stop the gimbal and release control for ``reason`` (in a task)."""
        self._epoch += 1
        self.turning = False
        if self._release is None or self._release.done():
            self._release = asyncio.get_running_loop().create_task(self._stop(reason), name="gimbal release")

    async def _stop(self, reason: str) -> None:
        await self.sender.settle()  # a send under way ends first: nothing takes control back after the release
        if not self.controller.gimbal_controlled:
            return
        try:
            async with asyncio.timeout(RELEASE_TIMEOUT_S):
                await self.controller.release_gimbal()
        except (ControllerError, TimeoutError) as exc:
            self.events.emit("error", "autonomy", f"gimbal not released ({reason}): "
                             f"{exc or f'no answer within {RELEASE_TIMEOUT_S:g} s'}")
        else:
            self.releases += 1
            self.events.emit("info", "autonomy", f"gimbal stopped and released: {reason}")

    @property
    def counts(self) -> dict[str, int]:
        return {"sent": self.sent, "failed": self.failed}

    @property
    def sent(self) -> int:
        return self.sender.sent

    @property
    def failed(self) -> int:
        return self.sender.failed

    async def close(self) -> None:
        """Wait for a release under way (the platform's exit: before the controller closes)."""
        if self._release is not None:
            await asyncio.gather(self._release, return_exceptions=True)
        await self.sender.close()


def say_no_gimbal(result: ProcessedFrame) -> str:
    """The flight controller has no gimbal control: ``result``'s pointing, if any, is not sent."""
    return "" if result.outcome.outputs.gimbal is None else "not sent: the flight controller has no gimbal control"
