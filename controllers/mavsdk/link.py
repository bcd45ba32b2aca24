"""What the autopilot says about itself: heartbeat age, current flight mode, readiness to arm.

The flight mode is MAVSDK's name where it has one, and the name :func:`controllers.flight_modes.decode` reads from
the HEARTBEAT where MAVSDK says ``UNKNOWN`` (PX4's Precision Land is ``PRECISION_LAND``, not ``UNKNOWN``).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
import time
from collections.abc import Callable
from typing import Any

from mavsdk.asyncio.plugins.mavlink_direct import MavlinkDirectAsync, MavlinkMessage
from mavsdk.asyncio.plugins.telemetry import FlightMode, TelemetryAsync

from controllers.flight_modes import MAVSDK_NAMES, decode
from controllers.mavsdk.calls import Subscriptions

MAV_AUTOPILOT_INVALID = 8
"""HEARTBEAT.autopilot of ground stations and other non-autopilot components."""

UNNAMED = "UNKNOWN"
"""MAVSDK's name for every mode it has no name for."""

MAV_SYS_STATUS_SENSOR_RC_RECEIVER = 0x10000
"""SYS_STATUS sensor bit of the RC receiver (PX4: any valid manual-control input, RC or joystick)."""

SYS_STATUS_WAIT_S = 3.0
"""How long to wait for a first SYS_STATUS (PX4 sends it at 1 Hz or more)."""


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
        self._mavsdk_mode: str | None = None
        """MAVSDK's name for the mode, as it last reported it."""
        self._decoded_mode: str | None = None
        """The mode decoded from the last HEARTBEAT."""
        self._listeners: list[Callable[[dict[str, Any]], None]] = []
        self._rc_receiver: bool | None = None
        self._sys_status = asyncio.Event()

    def start(self) -> None:
        """Follow heartbeats and flight modes until ``subscriptions`` is closed."""
        self._subscriptions.read(self._direct.subscribe_message("HEARTBEAT"), self._on_heartbeat, "mavsdk-heartbeat")
        self._subscriptions.read(self._telemetry.subscribe_flight_mode(), self._on_flight_mode, "mavsdk-flight-mode")
        self._subscriptions.read(self._direct.subscribe_message("SYS_STATUS"), self._on_sys_status, "mavsdk-sys-status")

    def heartbeat_age_s(self) -> float:
        """Seconds since the autopilot's last heartbeat."""
        return time.monotonic() - self._last_heartbeat

    def flight_mode_since(self, t_mono: float) -> str | None:
        """The flight mode last reported, if it arrived after ``t_mono`` (time.monotonic()).

        ArduCopter's GUIDED reads OFFBOARD and LOITER reads HOLD (MAVSDK's mapping); a mode MAVSDK calls ``UNKNOWN``
        reads as decoded from the HEARTBEAT (:mod:`controllers.flight_modes`).
        """
        mode, received = self._flight_mode
        return mode if received > t_mono else None

    def follow_modes(self, put: Callable[[dict[str, Any]], None]) -> asyncio.Task[None]:
        """Call ``put({"flight_mode": name})`` with each flight mode reported from now on (with the next HEARTBEAT, as
        MAVSDK's other HEARTBEAT fields), until the returned task is cancelled."""

        async def follow() -> None:
            self._listeners.append(put)
            try:
                await asyncio.Future()  # until cancelled
            finally:
                self._listeners.remove(put)

        return asyncio.create_task(follow(), name="telemetry-flight-mode")

    async def wait_ready(self, timeout_s: float) -> bool:
        """Wait until the autopilot reports it could arm (position estimate, home, pre-arm checks)."""
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(timeout_s):
                async with contextlib.aclosing(self._telemetry.subscribe_health()) as healths:
                    async for health in healths:
                        if health.is_armable and health.is_global_position_ok and health.is_home_position_ok:
                            return True
        return False

    async def rc_receiver_present(self, timeout_s: float = SYS_STATUS_WAIT_S) -> bool | None:
        """Whether the last SYS_STATUS shows the RC receiver present and healthy (waiting up to ``timeout_s`` for a
        first one); None when none arrived. Only *present* means a receiver: PX4 sets the health bit of an absent
        one too."""
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(timeout_s):
                await self._sys_status.wait()
        return self._rc_receiver

    def _on_sys_status(self, message: MavlinkMessage) -> None:
        if message.system_id != self._system_id:
            return
        with contextlib.suppress(KeyError, TypeError, ValueError):
            fields = json.loads(message.fields_json)
            bit = MAV_SYS_STATUS_SENSOR_RC_RECEIVER
            self._rc_receiver = bool(int(fields["onboard_control_sensors_present"]) & bit
                                     and int(fields["onboard_control_sensors_health"]) & bit)
            self._sys_status.set()

    def _on_heartbeat(self, message: MavlinkMessage) -> None:
        if message.system_id != self._system_id:
            return
        try:
            fields = json.loads(message.fields_json)
        except ValueError:
            fields = {}
        if fields.get("autopilot") == MAV_AUTOPILOT_INVALID:
            return
        self._last_heartbeat = time.monotonic()
        with contextlib.suppress(KeyError, TypeError, ValueError):
            self._decoded_mode = decode(*(int(fields[k]) for k in ("autopilot", "type", "base_mode", "custom_mode")))
            if self._mavsdk_mode == UNNAMED:  # the decoded name is the one in use (before MAVSDK's first: none)
                self._report(self._decoded_mode)

    def _on_flight_mode(self, mode: FlightMode) -> None:
        """MAVSDK's name is reported as it is, unless it is ``UNKNOWN``.

        For ``UNKNOWN``, the mode decoded from the HEARTBEAT is reported, unless it is one MAVSDK names: then it is
        the previous mode's (MAVSDK saw the new HEARTBEAT first), and the new one is reported when its HEARTBEAT
        arrives here.
        """
        name = self._mavsdk_mode = mode.name
        if name != UNNAMED:
            self._report(name)
        elif self._decoded_mode is not None and self._decoded_mode not in MAVSDK_NAMES:
            self._report(self._decoded_mode)

    def _report(self, name: str) -> None:
        self._flight_mode = (name, time.monotonic())
        for put in list(self._listeners):
            put({"flight_mode": name})
