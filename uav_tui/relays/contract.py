"""The contract every output relay keeps: the core builds one per registry entry from the run's parts
(:class:`RelayParts`) and calls it on each frame; what the gate, the lock and the relays did with a frame is its
:class:`HandledFrame`."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from controllers.base import FlightController
    from sources.buffer import Frame
    from uav_tui.camera.active import ActiveCamera
    from uav_tui.config import SafetyConfig
    from uav_tui.events import EventLog
    from uav_tui.flight.autonomy import AutonomyGate, Decision
    from uav_tui.flight.telemetry import TelemetryManager
    from uav_tui.flight.track_lock import LockStatus
    from uav_tui.hosting.host import ProcessedFrame
    from uav_tui.hosting.wire import FrameOutcome
    from uav_tui.relays.precland import LandingTargetFeed


class OutputRelay(Protocol):
    """Turns one processor output (``field`` of the frame's outputs) into an effect, gated and counted."""

    field: str
    """The output it relays (``gimbal``)."""

    def consider(self, result: ProcessedFrame) -> str:
        """Act on ``result``'s output now (on the loop, never blocking); returns what was done (``sent``, ``not sent:
        why``), "" for nothing (no output on the frame)."""

    def stop(self, reason: str) -> None:
        """Autonomy stopped for ``reason``: end any effect under way."""

    async def close(self) -> None:
        """The platform exits: wait for what is under way (before the controller closes)."""

    @property
    def counts(self) -> Mapping[str, int]:
        """What it did so far (``sent``, ``failed``)."""


@dataclasses.dataclass(frozen=True, slots=True)
class HandledFrame:
    """One processed frame and what the platform did with it, on the loop: what every frame listener gets (the
    recorder, the web page, the status) and the core keeps as its ``last``."""

    result: ProcessedFrame
    """The frame and its outcome as the gate and the relays saw it (the operator's lock: its steered copy)."""
    decision: Decision
    """What the autonomy gate did with the vector: ``executed`` or why not."""
    relayed: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """What each relay did with its output (:data:`~uav_tui.relays.registry.REGISTRY`), by field; a relay that did
    nothing is left out."""
    lock: LockStatus | None = None
    """The operator's lock on a track once it steered this frame (None: no lock)."""

    @property
    def frame(self) -> Frame:
        return self.result.frame

    @property
    def outcome(self) -> FrameOutcome:
        return self.result.outcome

    @property
    def landing(self) -> str:
        """What was done with the landing target: ``sent`` or why not ("" without one)."""
        return self.relayed.get("landing_target", "")

    @property
    def gimbal(self) -> str:
        """What was done with the gimbal pointing: ``sent`` or why not ("" without one)."""
        return self.relayed.get("gimbal", "")


@dataclasses.dataclass(frozen=True, slots=True)
class RelayParts:
    """The parts of a run a relay's build may use (:data:`~uav_tui.relays.registry.REGISTRY`), once the vehicle is
    connected."""

    controller: FlightController | None
    gate: AutonomyGate
    """The autonomy gate: its switch, its clock, its stop listeners."""
    telemetry: TelemetryManager
    events: EventLog
    camera: ActiveCamera
    """The source frames come from and its camera model (both follow a switch)."""
    landing: LandingTargetFeed
    """The landing targets seen and the operator's ``precland`` switch."""
    safety: SafetyConfig


@dataclasses.dataclass(slots=True)
class Unserved:
    """The relay of an output the controller cannot serve: ``say`` tells why of each frame's output (""
    without one), nothing is ever sent."""

    field: str
    say: Callable[[ProcessedFrame], str]
    counts: Mapping[str, int] = dataclasses.field(default_factory=dict)

    def consider(self, result: ProcessedFrame) -> str:
        return self.say(result)

    def stop(self, reason: str) -> None:
        """Nothing to stop."""

    async def close(self) -> None:
        """Nothing under way."""
