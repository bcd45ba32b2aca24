"""What the autopilot says about itself: heartbeat age, current flight mode, readiness to arm."""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
import time

from mavsdk.asyncio.plugins.mavlink_direct import MavlinkDirectAsync, MavlinkMessage
from mavsdk.asyncio.plugins.telemetry import FlightMode, TelemetryAsync

from controllers.mavsdk_calls import Subscriptions

MAV_AUTOPILOT_INVALID = 8
"""HEARTBEAT.autopilot of ground stations and other non-autopilot components."""


class LinkMonitor:
    """Follows the autopilot's HEARTBEAT and flight mode in two readers of ``subscriptions``.

    Args:
        direct: MavlinkDirect plugin of the autopilot's system (for raw HEARTBEATs).
        telemetry: Telemetry plugin of the same system.
        system_id: the autopilot's MAVLink system id; other senders are ignored.
        subscriptions: the controller's; closing it ends the monitor.
    """

    def __init__(self, direct: MavlinkDirectAsync, telemetry: TelemetryAsync, system_id: int,
                 subscriptions: Subscriptions) -> None:
        self._direct = direct
        self._telemetry = telemetry
        self._system_id = system_id
        self._subscriptions = subscriptions
        self._last_heartbeat = time.monotonic()  # connecting means one just arrived
        self._flight_mode: tuple[str | None, float] = (None, -math.inf)

    def start(self) -> None:
        """Follow heartbeats and flight modes until ``subscriptions`` is closed."""
        self._subscriptions.read(self._direct.subscribe_message("HEARTBEAT"), self._on_heartbeat, "mavsdk-heartbeat")
        self._subscriptions.read(self._telemetry.subscribe_flight_mode(), self._on_flight_mode, "mavsdk-flight-mode")

    def heartbeat_age_s(self) -> float:
        """Seconds since the autopilot's last heartbeat."""
        return time.monotonic() - self._last_heartbeat

    def flight_mode_since(self, t_mono: float) -> str | None:
        """The flight mode MAVSDK last reported, if it arrived after ``t_mono`` (time.monotonic()).

        ArduCopter's GUIDED reads OFFBOARD and LOITER reads HOLD (MAVSDK's mapping).
        """
        mode, received = self._flight_mode
        return mode if received > t_mono else None

    async def wait_ready(self, timeout_s: float) -> bool:
        """Wait until the autopilot reports it could arm (position estimate, home, pre-arm checks)."""
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(timeout_s):
                async with contextlib.aclosing(self._telemetry.subscribe_health()) as healths:
                    async for health in healths:
                        if health.is_armable and health.is_global_position_ok and health.is_home_position_ok:
                            return True
        return False

    def _on_heartbeat(self, message: MavlinkMessage) -> None:
        if message.system_id != self._system_id:
            return
        with contextlib.suppress(ValueError):
            if json.loads(message.fields_json).get("autopilot") == MAV_AUTOPILOT_INVALID:
                return
        self._last_heartbeat = time.monotonic()

    def _on_flight_mode(self, mode: FlightMode) -> None:
        self._flight_mode = (mode.name, time.monotonic())
