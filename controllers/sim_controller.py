"""``--fc sim``: start the built-in simulated vehicle and fly it through the real MAVSDK controller."""

from __future__ import annotations

import asyncio
import logging
from typing import Any

from controllers.mavsdk.controller import MavsdkController
from controllers.sim.launcher import SimVehicle

logger = logging.getLogger(__name__)

READY_TIMEOUT_S = 10.0
"""How long ``--fc sim`` waits for the simulated vehicle to be ready to arm."""


class SimController(MavsdkController):
    """A MavsdkController connected to a simulator process it owns; ``close()`` stops the simulator.

    Attributes:
        sim: the running :class:`SimVehicle` (``sim.truth()`` reaches its ground-truth channel).
    """

    def __init__(self, sim: SimVehicle, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.sim = sim

    async def close(self) -> None:
        """Close the MAVSDK side (holding first if a vector runs), then stop the simulator. Idempotent."""
        try:
            await super().close()
        finally:
            await asyncio.to_thread(self.sim.stop)


async def start_sim_controller(*, heartbeat_timeout: float = 10.0, **vehicle: Any) -> SimController:
    """Start a simulator process (``vehicle``: :class:`SimVehicle`'s home, wind, seed, noise) and connect to
    it; the simulator is stopped again if that fails."""
    sim = SimVehicle(**vehicle)
    starting = asyncio.ensure_future(asyncio.to_thread(sim.start))
    try:
        await asyncio.shield(starting)
    except asyncio.CancelledError:  # the spawn goes on in its thread: let it finish, then stop what it started
        await asyncio.gather(starting, return_exceptions=True)
        await asyncio.to_thread(sim.stop)
        raise
    controller = SimController(sim)
    try:
        await controller.connect(sim.connection_string, heartbeat_timeout=heartbeat_timeout)
        # So that a script's first "arm" finds the vehicle ready (GPS fix after ~1 s).
        if not await controller.wait_ready(READY_TIMEOUT_S):
            logger.warning("simulated vehicle not ready to arm after %.0f s", READY_TIMEOUT_S)
    except BaseException:
        await controller.close()
        raise
    controller.description = f"simulated vehicle ({controller.description})"
    return controller
