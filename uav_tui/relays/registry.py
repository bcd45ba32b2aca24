"""Which relays exist and the controller capability each needs; :func:`build_relays` makes the run's."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from controllers.base import GimbalControl, LandingTargets
from uav_tui.relays.contract import Unserved
from uav_tui.relays.gimbal import GimbalRelay, say_no_gimbal
from uav_tui.relays.landing_target import LandingTargetRelay, LandingTargetSender

if TYPE_CHECKING:
    from uav_tui.hosting.host import ProcessedFrame
    from uav_tui.relays.contract import OutputRelay, RelayParts


@dataclass(frozen=True, slots=True)
class RelayEntry:
    """One output: its field, the capability (a runtime-checkable Protocol) its controller needs, the relay's build,
    and the relay used instead when the controller lacks the capability (or there is none)."""

    field: str
    capability: type
    build: Callable[[RelayParts], OutputRelay]
    absent: Callable[[RelayParts], OutputRelay]


def _gimbal(parts: RelayParts) -> GimbalRelay:
    assert parts.controller is not None
    return GimbalRelay(parts.controller, parts.gate, parts.safety, parts.events)


def _landing_target(parts: RelayParts, sender: LandingTargetSender | None = None) -> LandingTargetRelay:
    """The landing targets' relay; without a ``sender`` the controller takes none (they are still judged and seen)."""
    return LandingTargetRelay(parts.landing, parts.telemetry, parts.camera, parts.gate, sender)


def _sent_landing_target(parts: RelayParts) -> LandingTargetRelay:
    assert isinstance(parts.controller, LandingTargets)
    return _landing_target(parts, LandingTargetSender(parts.controller, parts.events))


REGISTRY: list[RelayEntry] = [
    RelayEntry("landing_target", LandingTargets, _sent_landing_target, _landing_target),
    RelayEntry("gimbal", GimbalControl, _gimbal, lambda parts: Unserved("gimbal", say_no_gimbal)),
]
"""Every output relay, in the order the core calls them each frame (after the autonomy gate)."""


def build_relays(parts: RelayParts) -> dict[str, OutputRelay]:
    """The run's relays (field -> relay): each entry's build if ``parts.controller`` has its capability, else its
    ``absent``."""
    controller = parts.controller
    return {entry.field: entry.build(parts) if controller is not None and isinstance(controller, entry.capability)
            else entry.absent(parts) for entry in REGISTRY}


def consider_all(relays: dict[str, OutputRelay], result: ProcessedFrame) -> dict[str, str]:
    """Each relay acts on ``result``, in the registry's order; what each did, by field (those that did nothing left
    out)."""
    relayed = {field: relay.consider(result) for field, relay in relays.items()}
    return {field: verdict for field, verdict in relayed.items() if verdict}


def gimbal_relay(relays: dict[str, OutputRelay]) -> GimbalRelay | None:
    """The gimbal's relay among ``relays`` (None without a controller that points a gimbal)."""
    relay = relays.get("gimbal")
    return relay if isinstance(relay, GimbalRelay) else None


def landing_target_relay(relays: dict[str, OutputRelay]) -> LandingTargetRelay | None:
    """The landing targets' relay among ``relays`` (None before the core built them)."""
    relay = relays.get("landing_target")
    return relay if isinstance(relay, LandingTargetRelay) else None
