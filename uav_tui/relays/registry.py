"""Which relays exist and the controller capability each needs; :func:`build_relays` makes the run's."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from controllers.base import GimbalControl
from uav_tui.flight.gimbal_relay import GimbalRelay, consider_gimbal

if TYPE_CHECKING:
    from controllers.base import FlightController
    from uav_tui.config import SafetyConfig
    from uav_tui.events import EventLog
    from uav_tui.flight.autonomy import AutonomyGate
    from uav_tui.hosting.host import ProcessedFrame
    from uav_tui.relays.contract import OutputRelay


@dataclass(frozen=True, slots=True)
class RelayEntry:
    """One output: its field, the capability (a runtime-checkable Protocol) its controller needs, and the build."""

    field: str
    capability: type
    build: Callable[[FlightController, AutonomyGate, SafetyConfig, EventLog], OutputRelay]


REGISTRY: list[RelayEntry] = [
    RelayEntry("gimbal", GimbalControl, GimbalRelay),
]
"""Every output relay, in the order the core calls them each frame (after the autonomy gate)."""


def build_relays(controller: FlightController | None, gate: AutonomyGate, safety: SafetyConfig,
                 events: EventLog) -> dict[str, OutputRelay]:
    """The relays ``controller`` can serve (field -> relay); an entry whose capability it lacks gets none."""
    return {entry.field: entry.build(controller, gate, safety, events) for entry in REGISTRY
            if controller is not None and isinstance(controller, entry.capability)}


def consider_all(relays: dict[str, OutputRelay], result: ProcessedFrame) -> None:
    """Each relay acts on ``result``; a gimbal pointing without a gimbal's relay is said not sent."""
    for relay in relays.values():
        relay.consider(result)
    if "gimbal" not in relays:
        consider_gimbal(None, result)


def gimbal_relay(relays: dict[str, OutputRelay]) -> GimbalRelay | None:
    """The gimbal's relay among ``relays`` (None without a controller that points a gimbal)."""
    relay = relays.get("gimbal")
    return relay if isinstance(relay, GimbalRelay) else None
