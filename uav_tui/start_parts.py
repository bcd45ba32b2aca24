"""The two slow parts of a start, at once: the processor's host loading and the vehicle connecting."""

from __future__ import annotations

import asyncio
from collections.abc import Callable

from controllers import connect_controller
from controllers.base import FlightController
from uav_tui.config import Config
from uav_tui.events import EventLog
from uav_tui.hosting.host import ProcessedFrame, ProcessorHost
from uav_tui.hosting.start import start_host


async def load_and_connect(config: Config, on_result: Callable[[ProcessedFrame], None], events: EventLog,
                           on_fault: Callable[[str], None]) -> tuple[ProcessorHost, FlightController | None]:
    """Start the processor's host and connect ``config.fc`` together (each spawns a process: about a second).

    Whichever fails first cancels the other and is raised (it says what to fix); what did start is closed.
    """
    host: ProcessorHost | None = None
    controller: FlightController | None = None

    async def load() -> None:
        nonlocal host
        host = await start_host(config, on_result, events, on_fault)

    async def connect() -> None:
        nonlocal controller
        controller = await connect_controller(config.fc, heartbeat_timeout=config.connect_timeout,
                                              sim_vehicle=config.sim.vehicle())

    try:
        async with asyncio.TaskGroup() as parts:
            parts.create_task(load(), name="load the processor")
            parts.create_task(connect(), name="connect the vehicle")
    except BaseException as exc:
        if host is not None:
            host.close()
        if controller is not None:
            await controller.close()
        if isinstance(exc, BaseExceptionGroup):
            raise exc.exceptions[0] from None
        raise
    assert host is not None
    return host, controller
