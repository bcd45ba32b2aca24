"""``--fc sim``: start the built-in simulated vehicle and fly it through the real MAVSDK controller."""

from __future__ import annotations

import asyncio
import logging

from controllers.mavsdk_controller import MavsdkController
from controllers.sim.launcher import SimVehicle

logger = logging.getLogger(__name__)


class SimController(MavsdkController):
    """A MavsdkController connected to a simulator process it owns; ``close()`` stops the simulator.

    Attributes:
        sim: the running :class:`SimVehicle` (``sim.truth()`` reaches its ground-truth channel).
    """

    def __init__(self, sim: SimVehicle, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.sim = sim

    async def close(self) -> None:
        """Close the MAVSDK side (holding first if a vector runs), then stop the simulator. Idempotent."""
        try:
            await super().close()
        finally:
            await asyncio.to_thread(self.sim.stop)


async def start_sim_controller(*, heartbeat_timeout: float = 10.0) -> SimController:
    """Start a simulator process and connect to it; the simulator is stopped again if that fails."""
    sim = SimVehicle()
    await asyncio.to_thread(sim.start)
    controller = SimController(sim)
    try:
        await controller.connect(sim.connection_string, heartbeat_timeout=heartbeat_timeout)
    except BaseException:
        await controller.close()
        raise
    controller.description = f"simulated vehicle ({controller.description})"
    return controller
