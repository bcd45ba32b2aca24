"""How a run's parts are made: the two slow ones at once (the processor's host loading, the vehicle connecting), then
each wired to the parts it uses, once (:func:`build_parts`). The core owns the record this returns (:class:`Parts`);
each helper is given the few parts it uses."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from dataclasses import dataclass

from controllers import connect_controller
from controllers.base import FlightController, RecordedVehicle
from controllers.replay_timeline import ReplayTimeline
from uav_tui.camera.active import ActiveCamera
from uav_tui.config import Config
from uav_tui.events import EventLog
from uav_tui.flight.autonomy import AutonomyGate
from uav_tui.flight.clock_check import ClockCheck
from uav_tui.flight.link import LinkWatch
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.flight.track_lock import TrackLock
from uav_tui.hosting.host import ProcessedFrame, ProcessorHost
from uav_tui.hosting.start import start_host
from uav_tui.relays.contract import OutputRelay, RelayParts
from uav_tui.relays.precland import LandingTargetFeed
from uav_tui.relays.registry import build_relays
from uav_tui.replay.gate import ReplayGate, stage_clock


@dataclass(frozen=True, slots=True)
class Parts:
    """The long-lived parts of a started run, each built once (:func:`build_parts`)."""

    config: Config
    events: EventLog
    camera: ActiveCamera
    """The source frames come from and its camera model (both follow a switch)."""
    lock: TrackLock
    """The operator's lock on a track: while on, its vector is the frame's (``lock ID``, ``unlock``)."""
    landing: LandingTargetFeed
    """The processor's landing targets and the operator's ``precland`` switch."""
    worker: ProcessorHost
    """The processor's host (a thread or a process)."""
    controller: FlightController | None
    """The vehicle; None with ``--fc none``."""
    telemetry: TelemetryManager
    gate: AutonomyGate
    """The autonomy gate (a replay's: :class:`~uav_tui.replay.gate.ReplayGate`)."""
    relays: dict[str, OutputRelay]
    """The output relays by field, each for this controller (:func:`~uav_tui.relays.registry.build_relays`)."""
    replay: ReplayTimeline | None
    """Where a replay is on the recorded clock (``--fc replay:RUN``), else None."""
    link: LinkWatch | None
    """Link-loss / recovery events and the dead-simulator report (None without a flight controller)."""


async def build_parts(config: Config, events: EventLog, camera: ActiveCamera, lock: TrackLock,
                      landing: LandingTargetFeed, on_result: Callable[[ProcessedFrame], None],
                      on_fault: Callable[[str], None]) -> Parts:
    """Start the processor's host and connect the vehicle (:func:`load_and_connect`), then wire the parts: the
    telemetry to the vehicle, the autonomy gate (a replay's judges on the recorded clock) to both, the camera to the
    vehicle and the replay's clock, a relay to each output.

    Raises what the first failure says to fix (a ConfigError: an envelope that cannot be used); what did start is
    closed.
    """
    worker, controller = await load_and_connect(config, on_result, events, on_fault)
    try:
        telemetry = TelemetryManager(controller)
        replay = None
        gate: AutonomyGate
        if isinstance(controller, RecordedVehicle):
            replay = controller.timeline
            gate = ReplayGate(config.safety, telemetry, events, controller)
            worker.stage_clock = stage_clock(replay)
        else:
            gate = AutonomyGate(config.safety, telemetry, events)
            if controller is not None:
                telemetry.add_listener(ClockCheck(events))  # a replay's clock was the recording's
        gate.bind(telemetry, controller, config)
        camera.controller, camera.replay = controller, replay
        relays = build_relays(RelayParts(controller, gate, telemetry, events, camera, landing, config.safety))
        link = None if controller is None else LinkWatch(controller, events, config.safety.link_timeout)
    except BaseException:
        await _close(worker, controller)
        raise
    return Parts(config, events, camera, lock, landing, worker, controller, telemetry, gate, relays, replay, link)


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
        await _close(host, controller)
        if isinstance(exc, BaseExceptionGroup):
            raise exc.exceptions[0] from None
        raise
    assert host is not None
    return host, controller


async def _close(host: ProcessorHost | None, controller: FlightController | None) -> None:
    """Close what a failed start did start."""
    if host is not None:
        host.close()
    if controller is not None:
        await controller.close()
