"""The landing-target relay: each frame's landing target judged, then sent to the autopilot (LANDING_TARGET,
converted by the controller) while ``precland`` (:mod:`uav_tui.relays.precland`) or autonomy is on; and the
watchdog that turns ``precland`` off.
"""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING, Protocol

from controllers.base import PrecisionLanding
from controllers.landing_target_message import LandingTargetFix
from uav_tui.flight.autonomy import WATCHDOG_PERIOD_S
from uav_tui.flight.relay import SEND_TIMEOUT_S, OneAtATime, not_now
from uav_tui.relays.contract import RelayCore

if TYPE_CHECKING:
    from controllers.base import LandingTargets, Telemetry
    from uav_tui.events import EventLog
    from uav_tui.hosting.host import ProcessedFrame, ProcessorHost
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
    ``precland`` or autonomy is on, the frame fresh and the link alive; ``result.landing`` says what was done
    (frames.csv). A run of refusals turns ``precland`` off (the ``landing_target``
    :class:`~uav_tui.relays.contract.OutputRelay`).

    Args:
        core: the core (its landing feed, telemetry, camera model, gate and ``stop_precland``).
        sender: sends the targets; None: the flight controller takes none (they are still judged and seen).
    """

    def __init__(self, core: RelayCore, sender: LandingTargetSender | None) -> None:
        self.field = "landing_target"
        self.core = core
        self.sender = sender

    def consider(self, result: ProcessedFrame) -> None:
        core = self.core
        target = result.outcome.outputs.landing_target
        landing = core.landing
        if target is None:
            status = result.outcome.outputs.landing_status
            landing.why_none = f"the processor says: {status}" if status else ""  # not an older frame's reason
            return
        if core.camera is None:
            result.landing = "not sent: no camera model to check it against"
            landing.why_none = "no camera model to check the target against (set camera_hfov or a calibration file)"
            return
        capture_ns = result.frame.t_mono_ns
        at_capture = core.telemetry.at(capture_ns)[0]
        judged = landing.check.judge(target, result.frame.seq, capture_ns, core.camera, at_capture)
        if judged.target is None:
            result.landing = landing.why_none = f"refused: {judged.reason}"
            if landing.refusals.refuse(judged.reason) and landing.engaged:
                core.stop_precland(f"{landing.refusals.in_a_row} landing targets in a row refused, the last: "
                                   f"{judged.reason}; the autopilot's own landing goes on without them")
            return
        landing.refusals.accept()
        landing.why_none = ""
        landing.seen(capture_ns)
        why = self._blocked(capture_ns)
        result.landing = f"not sent: {why}" if why else "sent"
        if why:
            return
        assert self.sender is not None
        self.sender.send(landing_fix(judged.target, capture_ns, core.camera, at_capture))

    def _blocked(self, capture_ns: int) -> str:
        """Why a landing target seen in the frame captured at ``capture_ns`` is not sent now, or ""."""
        core = self.core
        if not (core.landing.engaged or core.gate.enabled):
            return "precland and autonomy off"
        if self.sender is None or core.controller is None:
            return "the flight controller takes no landing targets"
        return not_now(core.controller, core.config.safety, (core.gate.clock() - capture_ns) / 1e9, self.sender)

    def stop(self, reason: str) -> None:
        """Nothing to end: each target is sent on its own (``precland`` has its own end, ``stop_precland``)."""

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


class LandingCore(RelayCore, Protocol):
    """What :func:`watch_precland` reads of the core besides what the relay reads, and how it stops ``precland``."""

    @property
    def worker(self) -> ProcessorHost | None: ...

    def newest_frame_age(self) -> float | None: ...

    def stop_precland(self, reason: str, *, landed: bool = False) -> None: ...


async def watch_precland(core: LandingCore) -> None:
    """Turn ``precland`` off on the faults that stop autonomy, once the vehicle landed and disarmed, and when it
    leaves its precision-landing mode (:meth:`LandingTargetFeed.left_mode`)."""
    worker = core.worker
    assert worker is not None
    while True:
        await asyncio.sleep(WATCHDOG_PERIOD_S)
        if not core.landing.engaged:
            continue
        fault = core.gate.fault(core.newest_frame_age(), worker.busy_s, worker.consecutive_errors)
        snapshot = core.telemetry.snapshot()
        if not fault and snapshot.armed is False:
            core.stop_precland("landed and disarmed", landed=True)
            continue
        if not fault and isinstance(core.controller, PrecisionLanding):
            fault = core.landing.left_mode(snapshot.flight_mode, core.controller.landing_modes)
        if fault:
            core.stop_precland(fault)
