"""Flight controllers: the contract is in :mod:`controllers.base`; :func:`connect_controller` picks one.

==================================  ==========================================================
address                              controller
==================================  ==========================================================
``none``                             no vehicle (returns None)
``sim``                              the built-in simulated vehicle, started and stopped with it
``replay:RUN[?speed=S|max]``         the recorded vehicle of a run folder (:mod:`controllers.replay`)
anything else                        :class:`controllers.mavsdk.controller.MavsdkController`
==================================  ==========================================================

Implementations are imported on first use, so ``--fc none`` never loads MAVSDK.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from controllers.base import FlightController, Telemetry
from controllers.errors import ConnectError

__all__ = ["FlightController", "Telemetry", "connect_controller"]


async def connect_controller(address: str, *, heartbeat_timeout: float = 10.0,
                             sim_vehicle: Mapping[str, Any] | None = None) -> FlightController | None:
    """Connect the flight controller named by ``address``.

    Args:
        address: ``none``, ``sim``, or a MAVLink connection string (``serial:///dev/ttyAMA0:57600``,
            ``udpin://0.0.0.0:14540``, ``tcpout://HOST:PORT``, ``udp://:14540``, ...).
        heartbeat_timeout: seconds to wait for the autopilot's first heartbeat.
        sim_vehicle: for ``sim``: home, wind, seed, noise of the simulated vehicle
            (:class:`controllers.sim.launcher.SimVehicle`'s arguments).

    Returns:
        A connected controller, or None for ``none``.

    Raises:
        ConnectError: bad address, missing/busy device, no heartbeat in time.
    """
    key = address.strip().lower()
    if key in ("none:", "sim:"):  # the camera's URIs have the colon (``--source sim:``), these names do not
        raise ConnectError(f"flight controller {address!r}: did you mean {key[:-1]!r} (without the colon)?")
    if key == "none":
        return None
    if key == "sim":
        from controllers.sim_controller import start_sim_controller

        return await start_sim_controller(heartbeat_timeout=heartbeat_timeout, **(sim_vehicle or {}))
    if key.isidentifier():  # a bare name (simulator, px4, ardupilot): not a connection string
        raise ConnectError(f"flight controller {address!r} is not a name uav-tui knows: use 'sim' for the built-in "
                           "simulated vehicle, 'none' for no vehicle, or a MAVLink connection string "
                           "(a PX4 SITL: udpin://0.0.0.0:14540; a flight controller on the Pi's UART: "
                           "serial:///dev/ttyAMA0:57600)")
    if key.startswith("replay:"):
        from controllers.replay import ReplayController

        return ReplayController.open(address)
    from controllers.mavsdk.controller import MavsdkController

    controller = MavsdkController()
    await controller.connect(address, heartbeat_timeout=heartbeat_timeout)
    return controller
