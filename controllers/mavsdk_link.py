"""What the autopilot says about itself: heartbeat age, current flight mode, readiness to arm."""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
import time

from mavsdk.asyncio.plugins.mavlink_direct import MavlinkDirectAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync

MAV_AUTOPILOT_INVALID = 8
"""HEARTBEAT.autopilot of ground stations and other non-autopilot components."""


class LinkMonitor:
    """Follows the autopilot's HEARTBEAT and flight mode in two background tasks.

    Args:
        direct: MavlinkDirect plugin of the autopilot's system (for raw HEARTBEATs).
        telemetry: Telemetry plugin of the same system.
        system_id: the autopilot's MAVLink system id; other senders are ignored.
    """

    def __init__(self, direct: MavlinkDirectAsync, telemetry: TelemetryAsync, system_id: int) -> None:
        self._direct = direct
        self._telemetry = telemetry
        self._system_id = system_id
        self._last_heartbeat = time.monotonic()  # connecting means one just arrived
        self._flight_mode: tuple[str | None, float] = (None, -math.inf)
        self._tasks: list[asyncio.Task[None]] = []

    def start(self) -> None:
        self._tasks = [
            asyncio.create_task(self._watch_heartbeats(), name="mavsdk-heartbeat"),
            asyncio.create_task(self._watch_flight_mode(), name="mavsdk-flight-mode"),
        ]

    async def stop(self) -> None:
        for task in self._tasks:
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)

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
                async for health in self._telemetry.subscribe_health():
                    if health.is_armable and health.is_global_position_ok and health.is_home_position_ok:
                        return True
        return False

    async def _watch_heartbeats(self) -> None:
        async for msg in self._direct.subscribe_message("HEARTBEAT"):
            if msg.system_id != self._system_id:
                continue
            with contextlib.suppress(ValueError):
                if json.loads(msg.fields_json).get("autopilot") == MAV_AUTOPILOT_INVALID:
                    continue
            self._last_heartbeat = time.monotonic()

    async def _watch_flight_mode(self) -> None:
        async for mode in self._telemetry.subscribe_flight_mode():
            self._flight_mode = (mode.name, time.monotonic())
