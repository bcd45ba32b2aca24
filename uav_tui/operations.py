"""What each operator command does to a running core's parts: :meth:`Operations.execute` logs and dispatches.

The commands are given the run's parts (:class:`~uav_tui.start_parts.Parts`), its recorder, its processor errors
and its quit request, and change them directly (the camera switched, the processor's error cleared); the mode a
vehicle command handed the vehicle to is theirs (:attr:`Operations.handed_over`).
"""

from __future__ import annotations

import asyncio
import functools
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any, NamedTuple

from controllers.base import PrecisionLanding
from processors.outputs import READERS
from uav_tui.errors import KNOWN_ERRORS, CommandError, NoVehicle, ProcessorLoadError, SourceError, UavError
from uav_tui.flight.autonomy import check_vector
from uav_tui.flight.commands import VEHICLE_COMMANDS, Command, check_limits, unknown_command
from uav_tui.flight.track_lock import LockState
from uav_tui.hosting.child_link import ProcessorRaised
from uav_tui.hosting.host import Answer
from uav_tui.hosting.operator_calls import ProcessorCalls
from uav_tui.hosting.start import say_load_warnings
from uav_tui.output.text import describe, shorten
from uav_values.camera import CameraModelError

if TYPE_CHECKING:
    from controllers.base import FlightController
    from uav_tui.hosting.exception_reports import ProcessorErrors
    from uav_tui.recording import Recorder
    from uav_tui.start_parts import Parts

HANDED_OVER = {"land": "LAND", "precland": "LAND", "rtl": "RETURN_TO_LAUNCH"}
"""Commands that hand the vehicle to the autopilot's own mode (MAVSDK's name): exit leaves it there."""

PLAIN_VEHICLE_CALLS: dict[str, tuple[Callable[[FlightController], Awaitable[None]], str]] = {
    "arm": (lambda fc: fc.arm(), "armed"),
    "disarm": (lambda fc: fc.disarm(), "disarmed"),
    "land": (lambda fc: fc.land(), "landing"),
    "rtl": (lambda fc: fc.return_to_home(), "returning to launch"),
    "hold": (lambda fc: fc.hold(), "holding"),
}
"""Commands that are one FlightController call without arguments: word -> (the call, what to report)."""


class Outcome(NamedTuple):
    """What a command did, and when, if that was before it returned."""

    message: str
    t_mono_ns: int | None = None
    """When it took effect (monotonic ns); None: when it returned. A processor call took effect when the
    processor began it: the frames it started after that saw it (a replay gives it before the same frame)."""


Handler = Callable[..., Awaitable[Outcome | str]]
"""One command's coroutine: called with the command's arguments and ``origin=``; returns what happened."""


class Operations:
    """One coroutine per command word; each returns what happened or raises UavError saying why not.

    Args:
        parts: the run's parts the commands act on.
        recorder: the run's recorder (``snapshot``, and a camera switch), None with ``--no-record``.
        errors: the processor's errors (``reload`` clears the last one).
        quit_requested: set by ``quit``.
    """

    def __init__(self, parts: Parts, recorder: Recorder | None, errors: ProcessorErrors,
                 quit_requested: asyncio.Event) -> None:
        self.parts = parts
        self.recorder = recorder
        self.errors = errors
        self.quit_requested = quit_requested
        self.handed_over: str | None = None
        """The mode (MAVSDK's name) the last vehicle command handed the vehicle to: LAND after ``land``,
        RETURN_TO_LAUNCH after ``rtl``; None after any other vehicle command."""
        self._processor_calls = ProcessorCalls()
        self.handlers: dict[str, Handler] = {
            **{word: functools.partial(self._plain, call, done) for word, (call, done) in PLAIN_VEHICLE_CALLS.items()},
            "takeoff": self._takeoff, "orbit": self._orbit, "precland": self._precland, "vector": self._vector,
            "autonomy": self._autonomy, "f": self._f, "roi": self._roi, "lock": self._lock, "unlock": self._unlock,
            "snapshot": self._snapshot,
            "reload": self._reload, "source": self._source, "wait": self._wait, "quit": self._quit,
        }
        """Each command word's coroutine (every word of :data:`~uav_tui.flight.commands.COMMANDS`)."""

    async def execute(self, command: Command, origin: str) -> str:
        """Run one operator command of a running core; returns what happened, raises UavError saying why it could
        not.

        Logged as it comes and as it ends (or fails); a vehicle command needs a flight controller and
        pre-empts autonomy at once.
        """
        parts = self.parts
        parts.events.emit("info", "command", str(command), origin)
        try:
            if command.word in VEHICLE_COMMANDS:
                if parts.controller is None:
                    raise NoVehicle(f"{command.word}: no flight controller (--fc none); use --fc sim or a "
                                    "MAVLink connection string")
                if parts.gate.enabled:  # any operator command pre-empts autonomy at once
                    await parts.gate.disable(origin, f"pre-empted by operator command '{command}'", hold=False)
                parts.gate.stop_flying_back()  # and its flight back to where the target was last seen
                if command.word != "precland":  # and a precision landing
                    parts.landing.end(f"pre-empted by operator command '{command}'")
                parts.lock.release(f"pre-empted by operator command '{command}'", origin)  # and the lock
            outcome = await self.run(command, origin)
        except KNOWN_ERRORS as exc:
            parts.events.emit("error", "command", f"{command}: {exc}", origin, command=str(command))
            raise
        if outcome.message:
            parts.events.emit("info", "command", outcome.message, origin, command=str(command),
                              t_mono_ns=outcome.t_mono_ns)
        return outcome.message

    async def run(self, command: Command, origin: str) -> Outcome:
        """Do what ``command`` says, unlogged (:meth:`execute` logs)."""
        handler = self.handlers.get(command.word)
        if handler is None:
            raise unknown_command(command.word)
        check_limits(command, self.parts.config.safety)
        outcome = await handler(*command.args, origin=origin)
        if command.word in VEHICLE_COMMANDS:
            self.handed_over = HANDED_OVER.get(command.word)
        return outcome if isinstance(outcome, Outcome) else Outcome(outcome)

    async def _plain(self, call: Callable[[FlightController], Awaitable[None]], done: str, *, origin: str) -> str:
        await call(self._vehicle())
        return done

    async def _takeoff(self, altitude: float | None = None, *, origin: str) -> str:
        altitude = altitude or self.parts.config.safety.takeoff_alt
        await self._vehicle().takeoff(altitude)
        return f"taking off to {altitude:g} m"

    async def _orbit(self, radius: float, speed: float, *, origin: str) -> str:
        await self._vehicle().do_orbit(radius, speed)
        return f"orbiting at {radius:g} m, {speed:g} m/s"

    async def _precland(self, *, origin: str) -> str:
        controller = self._vehicle()
        if not isinstance(controller, PrecisionLanding):
            raise UavError(f"precland: {controller.description} cannot land on a landing target (use land)")
        info = self.parts.worker.processor.info
        if "getLandingTarget" not in info.capabilities:
            raise UavError(f"precland: processor {info.name} has no getLandingTarget() method, so there is no "
                           "landing target to land on (use a processor that reports one, e.g. precision_land; "
                           "or land)")
        if self.parts.camera.model is None:
            raise UavError("precland: no camera model, so a landing target seen in the image can't be given in the "
                           "vehicle's frame: set camera_calibration or camera_hfov and camera_mount ([camera])")
        landing = self.parts.landing
        landing.check_fresh()
        landing.engage()  # the targets flow from the moment the autopilot starts landing
        try:
            return await controller.precision_land()
        except BaseException:
            landing.release("precland failed")
            raise

    async def _vector(self, vx: float, vy: float, t: float, *, origin: str) -> str:
        vector, note = check_vector((vx, vy, t), self.parts.config.safety)
        assert vector is not None  # parse() already rejected non-finite values and t <= 0
        await self._vehicle().set_fly_vector(*vector)
        return f"flying vector {vector}" + (f" ({note})" if note else "")

    async def _autonomy(self, switch: str, *, origin: str) -> str:
        gate = self.parts.gate
        if switch == "on" or (switch == "toggle" and not gate.enabled):
            gate.check_can_enable()  # the vehicle's reasons first
            self._check_gives_outputs()
            gate.enable(origin)
        else:
            await gate.disable(origin)
        return ""

    def _check_gives_outputs(self) -> None:
        """Refuse autonomy for a processor that has nothing it could fly on (no vector nor any output of
        :data:`~processors.outputs.READERS`) while no track is locked: switched on, it would look armed for a flight
        that never comes."""
        info = self.parts.worker.processor.info
        if self.parts.lock.state is not LockState.OFF or {"getPreparedVector", *READERS} & info.capabilities:
            return
        close = "; ".join(info.warnings)  # a misspelt getPreparedVector, most likely
        raise UavError(f"autonomy refused: processor {info.name} has no getPreparedVector() (nor getLandingTarget() "
                       "or getGimbalPointing()), so it gives the vehicle nothing to fly (lock a track to fly after it)"
                       + (f"; {close}" if close else ""))

    async def _f(self, button: int, *, origin: str) -> Outcome:
        answer = await self._call_processor("customize_processing", button)
        info = self.parts.worker.processor.info
        meaning = dict(info.buttons).get(button)
        returned = "" if answer.value is None else f", returned {describe(answer.value, 100)}"
        call = f"{info.name.rsplit(':', 1)[-1]}.customize_processing({button}) done{returned}"
        return Outcome(f"F{button} {meaning}: {call}" if meaning else f"F{button}: {call}", answer.t_taken_ns)

    async def _roi(self, x: int, y: int, w: int, h: int, *, origin: str) -> Outcome:
        source = self.parts.camera.source
        width, height = source.get_frame_size() if source else (0, 0)
        if w <= 0 or h <= 0 or x + w > width or y + h > height:
            raise CommandError(f"roi ({x}, {y}, {w}, {h}) is not inside the {width}x{height} frame", key="roi")
        answer = await self._call_processor("catch_cmd", (x, y, w, h))
        return Outcome(f"target region ({x}, {y}, {w}, {h}) sent to the processor", answer.t_taken_ns)

    async def _lock(self, track_id: int, *, origin: str) -> str:
        return self.parts.lock.lock(track_id, self.parts.camera.model, origin)

    async def _unlock(self, *, origin: str) -> str:
        return "" if self.parts.lock.release("operator", origin) else "nothing was locked"

    async def _snapshot(self, *, origin: str) -> str:
        if self.recorder is None:
            raise UavError("snapshot: recording is off (started with --no-record)")
        return self.recorder.snapshot()

    async def _reload(self, *, origin: str) -> str:
        worker = self.parts.worker
        name = worker.processor.info.name
        try:
            info = await worker.reload()
        except ProcessorLoadError as exc:
            raise ProcessorLoadError(f"reload failed, {name} keeps running: {exc}", path=exc.path,
                                     class_name=exc.class_name, missing=exc.missing) from exc
        self.errors.last = None  # the reloaded processor's last error is history
        say_load_warnings(info, self.parts.events)
        return f"processor {info.name} reloaded"

    async def _source(self, uri: str, *, origin: str) -> str:
        active = self.parts.camera
        new = await active.open(uri)
        try:
            camera = active.model_of(new)
        except (SourceError, CameraModelError):
            await asyncio.get_running_loop().run_in_executor(None, new.close)
            raise
        old = active.switch(new, camera)
        if self.recorder is not None:
            self.recorder.watch(new)  # before the worker attaches: each frame is copied before it is drawn on
        self.parts.worker.attach(new.buffer, camera)
        if old is not None:
            await asyncio.get_running_loop().run_in_executor(None, old.close)
        width, height = new.get_frame_size()
        return f"camera switched to {uri} ({width}x{height})"

    async def _wait(self, seconds: float, *, origin: str) -> str:
        raise CommandError("wait is for --script files only", key="command")

    async def _quit(self, *, origin: str) -> str:
        self.quit_requested.set()
        return "quit requested"

    def _vehicle(self) -> FlightController:
        assert self.parts.controller is not None  # execute() refuses vehicle commands without one
        return self.parts.controller

    async def _call_processor(self, method: str, *args: Any) -> Answer:
        """Call the processor's ``method`` (in order, bounded: :class:`ProcessorCalls`); its answer: what it returned
        and when it began the call (monotonic ns)."""
        worker = self.parts.worker
        loaded = worker.processor
        if method not in loaded.info.capabilities:
            raise UavError(f"processor {loaded.info.name} has no {method}() method")
        what = f"{loaded.info.name}.{method}{describe(args)}"
        try:
            answer = await self._processor_calls.call(what, lambda: worker.call(method, *args),
                                                      self.parts.config.processor_call_timeout)
        except UavError:
            raise
        except ProcessorRaised as exc:
            raise UavError(f"{what} raised {shorten(str(exc), 500)}") from exc
        except Exception as exc:  # the researcher's code raised (thread isolation): report it, keep running
            raise UavError(f"{what} raised {type(exc).__name__}: {shorten(str(exc), 500)}") from exc
        return answer
