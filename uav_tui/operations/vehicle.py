"""The vehicle commands (``arm`` ... ``precland``) and what any of them stops first (:class:`PreEmption`)."""

from __future__ import annotations

import functools
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING

from controllers.base import PrecisionLanding
from uav_tui.errors import NoVehicle, UavError
from uav_tui.flight.autonomy import check_vector
from uav_tui.flight.commands import Command

if TYPE_CHECKING:
    from controllers.base import FlightController
    from uav_tui.camera.active import ActiveCamera
    from uav_tui.config import SafetyConfig
    from uav_tui.flight.autonomy import AutonomyGate
    from uav_tui.flight.track_lock import TrackLock
    from uav_tui.hosting.host import ProcessorHost
    from uav_tui.operations.outcome import Handler
    from uav_tui.relays.precland import LandingTargetFeed

PLAIN_VEHICLE_CALLS: dict[str, tuple[Callable[[FlightController], Awaitable[None]], str]] = {
    "arm": (lambda fc: fc.arm(), "armed"),
    "disarm": (lambda fc: fc.disarm(), "disarmed"),
    "land": (lambda fc: fc.land(), "landing"),
    "rtl": (lambda fc: fc.return_to_home(), "returning to launch"),
    "hold": (lambda fc: fc.hold(), "holding"),
}
"""Commands that are one FlightController call without arguments: word -> (the call, what to report)."""


class PreEmption:
    """What a vehicle command does before it runs: it needs a vehicle, and it stops autonomy, its flight back, a
    precision landing (unless it is ``precland``) and the lock on a track, at once."""

    def __init__(self, controller: FlightController | None, gate: AutonomyGate, landing: LandingTargetFeed,
                 lock: TrackLock) -> None:
        self.controller = controller
        self.gate = gate
        self.landing = landing
        self.lock = lock

    async def __call__(self, command: Command, origin: str) -> None:
        if self.controller is None:
            raise NoVehicle(f"{command.word}: no flight controller (--fc none); use --fc sim or a "
                            "MAVLink connection string")
        why = f"pre-empted by operator command '{command}'"
        if self.gate.enabled:
            await self.gate.disable(origin, why, hold=False)
        self.gate.stop_flying_back()
        if command.word != "precland":
            self.landing.end(why)
        self.lock.release(why, origin)


class VehicleCommands:
    """The commands the vehicle carries out (each word of :data:`~uav_tui.flight.commands.VEHICLE_COMMANDS`).

    Args:
        controller: the vehicle (None with ``--fc none``: :class:`PreEmption` refuses these commands then).
        landing: the landing-target feed ``precland`` engages.
        worker: the processor's host (``precland`` needs a processor that reports landing targets).
        camera: the active camera (``precland`` needs its camera model).
        safety: the limits ``takeoff`` and ``vector`` keep.
    """

    def __init__(self, controller: FlightController | None, landing: LandingTargetFeed, worker: ProcessorHost,
                 camera: ActiveCamera, safety: SafetyConfig) -> None:
        self.controller = controller
        self.landing = landing
        self.worker = worker
        self.camera = camera
        self.safety = safety

    def handlers(self) -> dict[str, Handler]:
        return {**{word: functools.partial(self._plain, call, done)
                   for word, (call, done) in PLAIN_VEHICLE_CALLS.items()},
                "takeoff": self._takeoff, "orbit": self._orbit, "precland": self._precland, "vector": self._vector}

    async def _plain(self, call: Callable[[FlightController], Awaitable[None]], done: str, *, origin: str) -> str:
        await call(self._vehicle())
        return done

    async def _takeoff(self, altitude: float | None = None, *, origin: str) -> str:
        altitude = altitude or self.safety.takeoff_alt
        await self._vehicle().takeoff(altitude)
        return f"taking off to {altitude:g} m"

    async def _orbit(self, radius: float, speed: float, *, origin: str) -> str:
        await self._vehicle().do_orbit(radius, speed)
        return f"orbiting at {radius:g} m, {speed:g} m/s"

    async def _precland(self, *, origin: str) -> str:
        controller = self._vehicle()
        if not isinstance(controller, PrecisionLanding):
            raise UavError(f"precland: {controller.description} cannot land on a landing target (use land)")
        info = self.worker.processor.info
        if "getLandingTarget" not in info.capabilities:
            raise UavError(f"precland: processor {info.name} has no getLandingTarget() method, so there is no "
                           "landing target to land on (use a processor that reports one, e.g. precision_land; "
                           "or land)")
        if self.camera.model is None:
            raise UavError("precland: no camera model, so a landing target seen in the image can't be given in the "
                           "vehicle's frame: set camera_calibration or camera_hfov and camera_mount ([camera])")
        self.landing.check_fresh()
        self.landing.engage()  # the targets flow from the moment the autopilot starts landing
        try:
            return await controller.precision_land()
        except BaseException:
            self.landing.release("precland failed")
            raise

    async def _vector(self, vx: float, vy: float, t: float, *, origin: str) -> str:
        vector, note = check_vector((vx, vy, t), self.safety)
        assert vector is not None  # parse() already rejected non-finite values and t <= 0
        await self._vehicle().set_fly_vector(*vector)
        return f"flying vector {vector}" + (f" ({note})" if note else "")

    def _vehicle(self) -> FlightController:
        assert self.controller is not None  # PreEmption refuses vehicle commands without one
        return self.controller
