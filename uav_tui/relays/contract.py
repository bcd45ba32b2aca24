"""The contract every output relay keeps: the core builds one per registry entry from the run's parts
(:class:`RelayParts`) and calls it on each frame."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from controllers.base import FlightController
    from uav_tui.camera.active import ActiveCamera
    from uav_tui.config import SafetyConfig
    from uav_tui.events import EventLog
    from uav_tui.flight.autonomy import AutonomyGate
    from uav_tui.flight.telemetry import TelemetryManager
    from uav_tui.hosting.host import ProcessedFrame
    from uav_tui.relays.precland import LandingTargetFeed


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
    """The relay of an output the controller cannot serve: ``say`` tells each frame so, nothing is ever sent."""

    field: str
    say: Callable[[ProcessedFrame], None]
    counts: Mapping[str, int] = dataclasses.field(default_factory=dict)

    def consider(self, result: ProcessedFrame) -> None:
        self.say(result)

    def stop(self, reason: str) -> None:
        """Nothing to stop."""

    async def close(self) -> None:
        """Nothing under way."""
