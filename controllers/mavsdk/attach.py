"""Reaching one autopilot through MAVSDK: open the connection, wait for its heartbeat, tell PX4 from ArduPilot,
give the plugins a controller drives it with, and ask for the telemetry the platform reads."""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable
from dataclasses import dataclass

from mavsdk.asyncio import Autopilot as MavsdkAutopilot
from mavsdk.asyncio import Mavsdk, MavsdkConnectionError, System
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.mavlink_direct import MavlinkDirectAsync
from mavsdk.asyncio.plugins.param import ParamAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync

from controllers.autopilots import Autopilot
from controllers.connection import Connection, connection_failed, no_heartbeat_error
from controllers.mavsdk import ardupilot
from controllers.mavsdk.calls import bounded
from controllers.mavsdk.telemetry import set_rates

logger = logging.getLogger(__name__)

SETUP_TIMEOUT_S = 5.0
"""Upper bound on opening the connection, and on asking for telemetry rates after connecting."""

_KINDS = {MavsdkAutopilot.PX4: Autopilot.PX4, MavsdkAutopilot.ARDUPILOT: Autopilot.ARDUPILOT}
"""MAVSDK's autopilot types that the platform knows; any other is :attr:`Autopilot.UNKNOWN`."""


@dataclass(frozen=True)
class ReachedAutopilot:
    """The autopilot MAVSDK found: its system id and kind, and the plugins a controller drives it with."""

    system: System
    sysid: int
    autopilot: Autopilot
    """From the heartbeat's autopilot field."""
    action: ActionAsync
    telemetry: TelemetryAsync
    param: ParamAsync
    direct: MavlinkDirectAsync


async def reach_autopilot(mavsdk: Mavsdk, conn: Connection, heartbeat_timeout: float) -> ReachedAutopilot:
    """Open ``conn`` and wait for the first autopilot's heartbeat.

    Raises:
        ConnectError: MAVSDK could not open the connection, or no heartbeat within ``heartbeat_timeout`` seconds.
    """
    try:
        async with asyncio.timeout(SETUP_TIMEOUT_S):
            await mavsdk.add_any_connection(conn.url)
    except MavsdkConnectionError as exc:
        raise connection_failed(conn, str(exc)) from exc
    except TimeoutError as exc:
        raise connection_failed(conn, f"MAVSDK did not open it within {SETUP_TIMEOUT_S:g} s") from exc
    system = None
    with contextlib.suppress(TimeoutError):  # belt and braces over MAVSDK's own timeout
        async with asyncio.timeout(heartbeat_timeout + 2.0):
            system = await mavsdk.first_autopilot(timeout_s=heartbeat_timeout)
    if system is None:
        raise await no_heartbeat_error(conn, heartbeat_timeout)
    sysid = await system.get_system_id()
    kind = _KINDS.get(await system.autopilot_type(), Autopilot.UNKNOWN)
    return ReachedAutopilot(system, sysid, kind, ActionAsync(system), TelemetryAsync(system), ParamAsync(system),
                            MavlinkDirectAsync(system))


async def ask_for_telemetry(reached: ReachedAutopilot, heartbeat_age_s: Callable[[], float]) -> None:
    """ArduPilot's data streams, then MAVSDK's telemetry rates; a rate nobody answers keeps the current one."""
    if reached.autopilot is Autopilot.ARDUPILOT:
        await bounded("request_data_stream", lambda: ardupilot.request_streams(reached.direct, reached.sysid),
                      SETUP_TIMEOUT_S, heartbeat_age_s)
    try:
        async with asyncio.timeout(SETUP_TIMEOUT_S):
            await set_rates(reached.telemetry)
    except TimeoutError:
        logger.warning("telemetry rates: no answer within %.0f s; keeping the current rates", SETUP_TIMEOUT_S)
