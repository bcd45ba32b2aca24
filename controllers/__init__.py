"""Flight controllers (placeholder until the fc branch lands)."""

from __future__ import annotations

from controllers.base import FlightController, Telemetry

__all__ = ["FlightController", "Telemetry", "connect_controller"]


async def connect_controller(address: str, *, heartbeat_timeout: float = 10.0) -> FlightController | None:
    if address == "none":
        return None
    raise NotImplementedError(address)
