"""The landing-target relay: each frame's landing target judged, then sent to the autopilot (LANDING_TARGET,
converted by the controller) while ``precland`` (:mod:`uav_tui.relays.precland`) or autonomy is on; and the
watchdog that turns ``precland`` off.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import TYPE_CHECKING, cast

from controllers.base import PrecisionLanding
from controllers.landing_target_message import LandingTargetFix
from uav_tui.flight.autonomy import WATCHDOG_PERIOD_S
from uav_tui.flight.relay import SEND_TIMEOUT_S, OneAtATime, not_now

if TYPE_CHECKING:
    from controllers.base import FlightController, LandingTargets, Telemetry
    from uav_tui.camera.active import ActiveCamera
    from uav_tui.events import EventLog
    from uav_tui.flight.autonomy import AutonomyGate
    from uav_tui.flight.telemetry import TelemetryManager
    from uav_tui.hosting.host import ProcessedFrame, ProcessorHost
    from uav_tui.relays.precland import LandingTargetFeed
    from uav_values.camera import CameraModel
    from uav_values.landing_target import LandingTarget


def landing_fix(target: LandingTarget, capture_ns: int, camera: CameraModel, at_capture: Telemetry) -> LandingTargetFix:
    """The fix the controller converts for its autopilot: ``target`` with the camera's mounting and the vehicle's
    attitude and position at the frame's capture (None where the telemetry had none)."""
    t = at_capture
    attitude = (t.roll_deg, t.pitch_deg, t.yaw_deg)
    position = (t.north_m, t.east_m, t.down_m)
    return LandingTargetFix(
        capture_ns, target.direction, target.distance_m, camera.rotation_body_camera, camera.mount.offset_m,
        None if None in attitude else attitude,  # type: ignore[arg-type]
        None if None in position else position)  # type: ignore[arg-type]


class LandingTargetSender(OneAtATime):
    """Sends one landing target at a time to the controller (:class:`~uav_tui.flight.relay.OneAtATime`).

    Args:
        controller: the flight controller (a :class:`~controllers.base.LandingTargets`).
        events: the core's event log.
        timeout_s: the longest one send may take.
    """

    def __init__(self, controller: LandingTargets, events: EventLog, timeout_s: float = SEND_TIMEOUT_S) -> None:
        super().__init__(events, "landing target", timeout_s)
        self.controller = controller

    def send(self, fix: LandingTargetFix) -> None:
        """Start sending ``fix`` (on the loop); the caller checked :attr:`busy`."""
        self.start(lambda: self.controller.send_landing_target(fix))


class LandingTargetRelay:
    """Judges each frame's landing target (:class:`~uav_tui.flight.plausibility.LandingCheck`), then sends it while
    ``precland`` or autonomy is on, the frame fresh and the link alive; :meth:`consider` returns what was done
    (frames.csv's ``landing``). A run of refusals turns ``precland`` off (the ``landing_target``
    :class:`~uav_tui.relays.contract.OutputRelay`).

    Args:
        landing: the landing targets seen and the ``precland`` switch.
        telemetry: the vehicle's attitude and position at each frame's capture.
        camera: the camera model of the frames (it follows a switch).
        gate: the autonomy gate (its switch, its clock and its safety settings).
        sender: sends the targets; None: the flight controller takes none (they are still judged and seen).
    """

    def __init__(self, landing: LandingTargetFeed, telemetry: TelemetryManager, camera: ActiveCamera,
                 gate: AutonomyGate, sender: LandingTargetSender | None) -> None:
        self.field = "landing_target"
        self.landing = landing
        self.telemetry = telemetry
        self.camera = camera
        self.gate = gate
        self.sender = sender

    def consider(self, result: ProcessedFrame) -> str:
        """Judge ``result``'s landing target and send it if allowed now; returns what was done ("" without one)."""
        target = result.outcome.outputs.landing_target
        landing, camera = self.landing, self.camera.model
        if target is None:
            status = result.outcome.outputs.landing_status
            landing.why_none = f"the processor says: {status}" if status else ""  # not an older frame's reason
            return ""
        if camera is None:
            landing.why_none = "no camera model to check the target against (set camera_hfov or a calibration file)"
            return "not sent: no camera model to check it against"
        capture_ns = result.frame.t_mono_ns
        at_capture = self.telemetry.at(capture_ns)[0]
        judged = landing.check.judge(target, result.frame.seq, capture_ns, camera, at_capture)
        if judged.target is None:
            landing.why_none = f"refused: {judged.reason}"
            if landing.refusals.refuse(judged.reason) and landing.engaged:
                landing.end(f"{landing.refusals.in_a_row} landing targets in a row refused, the last: "
                            f"{judged.reason}; the autopilot's own landing goes on without them")
            return landing.why_none
        landing.refusals.accept()
        landing.why_none = ""
        landing.seen(capture_ns)
        if why := self._blocked(capture_ns):
            return f"not sent: {why}"
        assert self.sender is not None
        self.sender.send(landing_fix(judged.target, capture_ns, camera, at_capture))
        return "sent"

    def _blocked(self, capture_ns: int) -> str:
        """Why a landing target seen in the frame captured at ``capture_ns`` is not sent now, or ""."""
        if not (self.landing.engaged or self.gate.enabled):
            return "precland and autonomy off"
        if self.sender is None:
            return "the flight controller takes no landing targets"
        age_s = (self.gate.clock() - capture_ns) / 1e9
        return not_now(cast("FlightController", self.sender.controller), self.gate.safety, age_s, self.sender)

    async def watch(self, controller: FlightController | None, frame_age: Callable[[], float | None],
                    worker: ProcessorHost) -> None:
        """Turn ``precland`` off on the faults that stop autonomy (the newest frame's age, the processor's), once the
        vehicle landed and disarmed, and when it leaves ``controller``'s precision-landing mode
        (:meth:`LandingTargetFeed.left_mode`)."""
        landing = self.landing
        while True:
            await asyncio.sleep(WATCHDOG_PERIOD_S)
            if not landing.engaged:
                continue
            fault = self.gate.fault(frame_age(), worker.busy_s, worker.consecutive_errors)
            snapshot = self.telemetry.snapshot()
            if not fault and snapshot.armed is False:
                landing.end("landed and disarmed", self.sender.sent if self.sender is not None else None)
                continue
            if not fault and isinstance(controller, PrecisionLanding):
                fault = landing.left_mode(snapshot.flight_mode, controller.landing_modes)
            if fault:
                landing.end(fault)

    def stop(self, reason: str) -> None:
        """Nothing to end: each target is sent on its own (``precland`` has its own end: the feed's ``end``)."""

    async def close(self) -> None:
        """Wait for a send under way."""
        if self.sender is not None:
            await self.sender.close()

    @property
    def counts(self) -> dict[str, int]:
        return {"sent": self.sent, "failed": self.failed}

    @property
    def sent(self) -> int:
        return self.sender.sent if self.sender is not None else 0

    @property
    def failed(self) -> int:
        return self.sender.failed if self.sender is not None else 0
