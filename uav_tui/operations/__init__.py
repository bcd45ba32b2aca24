"""What each operator command does to a running core's parts: :meth:`Operations.execute` logs and dispatches.

The commands come in families, each given the few parts it acts on (:func:`build_operations` hands them out from the
run's :class:`~uav_tui.start_parts.Parts`): the vehicle's (:mod:`.vehicle`), autonomy and the lock
(:mod:`.autonomy`), the processor's calls and reload (:mod:`.processor`), the run's own (:mod:`.run`). The mode a
vehicle command handed the vehicle to is the dispatcher's (:attr:`Operations.handed_over`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from uav_tui.errors import KNOWN_ERRORS
from uav_tui.flight.commands import VEHICLE_COMMANDS, Command, check_limits, unknown_command
from uav_tui.operations.autonomy import AutonomyCommands
from uav_tui.operations.outcome import Handler, Outcome
from uav_tui.operations.processor import ProcessorCommands
from uav_tui.operations.run import RunCommands
from uav_tui.operations.vehicle import PreEmption, VehicleCommands

if TYPE_CHECKING:
    import asyncio

    from uav_tui.config import SafetyConfig
    from uav_tui.events import EventLog
    from uav_tui.hosting.exception_reports import ProcessorErrors
    from uav_tui.recording import Recorder
    from uav_tui.start_parts import Parts

HANDED_OVER = {"land": "LAND", "precland": "LAND", "rtl": "RETURN_TO_LAUNCH"}
"""Commands that hand the vehicle to the autopilot's own mode (MAVSDK's name): exit leaves it there."""


class Operations:
    """One coroutine per command word (:attr:`handlers`); each returns what happened or raises UavError saying why
    not.

    Args:
        events: the event log each command is logged in.
        safety: the limits a command's arguments keep.
        pre_empt: what a vehicle command stops before it runs.
        handlers: each command word's coroutine.
    """

    def __init__(self, events: EventLog, safety: SafetyConfig, pre_empt: PreEmption,
                 handlers: dict[str, Handler]) -> None:
        self.events = events
        self.safety = safety
        self.pre_empt = pre_empt
        self.handlers = handlers
        """Each command word's coroutine (every word of :data:`~uav_tui.flight.commands.COMMANDS`)."""
        self.handed_over: str | None = None
        """The mode (MAVSDK's name) the last vehicle command handed the vehicle to: LAND after ``land``,
        RETURN_TO_LAUNCH after ``rtl``; None after any other vehicle command."""

    async def execute(self, command: Command, origin: str) -> str:
        """Run one operator command of a running core; returns what happened, raises UavError saying why it could
        not.

        Logged as it comes and as it ends (or fails); a vehicle command needs a flight controller and
        pre-empts autonomy at once.
        """
        self.events.emit("info", "command", str(command), origin)
        try:
            if command.word in VEHICLE_COMMANDS:
                await self.pre_empt(command, origin)
            outcome = await self.run(command, origin)
        except KNOWN_ERRORS as exc:
            self.events.emit("error", "command", f"{command}: {exc}", origin, command=str(command))
            raise
        if outcome.message:
            self.events.emit("info", "command", outcome.message, origin, command=str(command),
                             t_mono_ns=outcome.t_mono_ns)
        return outcome.message

    async def run(self, command: Command, origin: str) -> Outcome:
        """Do what ``command`` says, unlogged (:meth:`execute` logs)."""
        handler = self.handlers.get(command.word)
        if handler is None:
            raise unknown_command(command.word)
        check_limits(command, self.safety)
        outcome = await handler(*command.args, origin=origin)
        if command.word in VEHICLE_COMMANDS:
            self.handed_over = HANDED_OVER.get(command.word)
        return outcome if isinstance(outcome, Outcome) else Outcome(outcome)


def build_operations(parts: Parts, recorder: Recorder | None, errors: ProcessorErrors,
                     quit_requested: asyncio.Event) -> Operations:
    """The commands of a started run: each family given the parts it acts on.

    Args:
        parts: the run's parts.
        recorder: the run's recorder, None with ``--no-record``.
        errors: the processor's errors (``reload`` clears the last one).
        quit_requested: set by ``quit``.
    """
    config = parts.config
    families = (VehicleCommands(parts.controller, parts.landing, parts.worker, parts.camera, config.safety),
                AutonomyCommands(parts.gate, parts.lock, parts.worker, parts.camera),
                ProcessorCommands(parts.worker, parts.camera, errors, parts.events, config.processor_call_timeout),
                RunCommands(parts.camera, parts.worker, recorder, quit_requested))
    handlers = {word: handler for family in families for word, handler in family.handlers().items()}
    return Operations(parts.events, config.safety,
                      PreEmption(parts.controller, parts.gate, parts.landing, parts.lock), handlers)
