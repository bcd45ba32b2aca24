"""The operator's calls into the processor (``f N``, ``roi``) and ``reload``."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from uav_tui.errors import CommandError, ProcessorLoadError, UavError
from uav_tui.hosting.child_link import ProcessorRaised
from uav_tui.hosting.operator_calls import ProcessorCalls
from uav_tui.hosting.start import say_load_warnings
from uav_tui.operations.outcome import Outcome
from uav_tui.output.text import describe, shorten

if TYPE_CHECKING:
    from uav_tui.camera.active import ActiveCamera
    from uav_tui.events import EventLog
    from uav_tui.hosting.exception_reports import ProcessorErrors
    from uav_tui.hosting.host import Answer, ProcessorHost
    from uav_tui.operations.outcome import Handler


class ProcessorCommands:
    """``f``, ``roi`` and ``reload``.

    Args:
        worker: the processor's host, called between two frames.
        camera: the active camera (a region must lie inside its frames).
        errors: the processor's errors (``reload`` clears the last one).
        events: the event log (``reload`` tells the new code's load warnings).
        timeout: ``processor_call_timeout``, seconds.
    """

    def __init__(self, worker: ProcessorHost, camera: ActiveCamera, errors: ProcessorErrors, events: EventLog,
                 timeout: float) -> None:
        self.worker = worker
        self.camera = camera
        self.errors = errors
        self.events = events
        self.timeout = timeout
        self._calls = ProcessorCalls()

    def handlers(self) -> dict[str, Handler]:
        return {"f": self._f, "roi": self._roi, "reload": self._reload}

    async def _f(self, button: int, *, origin: str) -> Outcome:
        answer = await self._call_processor("customize_processing", button)
        info = self.worker.processor.info
        meaning = dict(info.buttons).get(button)
        returned = "" if answer.value is None else f", returned {describe(answer.value, 100)}"
        call = f"{info.name.rsplit(':', 1)[-1]}.customize_processing({button}) done{returned}"
        return Outcome(f"F{button} {meaning}: {call}" if meaning else f"F{button}: {call}", answer.t_taken_ns)

    async def _roi(self, x: int, y: int, w: int, h: int, *, origin: str) -> Outcome:
        source = self.camera.source
        width, height = source.get_frame_size() if source else (0, 0)
        if w <= 0 or h <= 0 or x + w > width or y + h > height:
            raise CommandError(f"roi ({x}, {y}, {w}, {h}) is not inside the {width}x{height} frame", key="roi")
        answer = await self._call_processor("catch_cmd", (x, y, w, h))
        return Outcome(f"target region ({x}, {y}, {w}, {h}) sent to the processor", answer.t_taken_ns)

    async def _reload(self, *, origin: str) -> str:
        name = self.worker.processor.info.name
        try:
            info = await self.worker.reload()
        except ProcessorLoadError as exc:
            raise ProcessorLoadError(f"reload failed, {name} keeps running: {exc}", path=exc.path,
                                     class_name=exc.class_name, missing=exc.missing) from exc
        self.errors.last = None  # the reloaded processor's last error is history
        say_load_warnings(info, self.events)
        return f"processor {info.name} reloaded"

    async def _call_processor(self, method: str, *args: Any) -> Answer:
        """Call the processor's ``method`` (in order, bounded: :class:`ProcessorCalls`); its answer: what it returned
        and when it began the call (monotonic ns)."""
        worker = self.worker
        loaded = worker.processor
        if method not in loaded.info.capabilities:
            raise UavError(f"processor {loaded.info.name} has no {method}() method")
        what = f"{loaded.info.name}.{method}{describe(args)}"
        try:
            answer = await self._calls.call(what, lambda: worker.call(method, *args), self.timeout)
        except UavError:
            raise
        except ProcessorRaised as exc:
            raise UavError(f"{what} raised {shorten(str(exc), 500)}") from exc
        except Exception as exc:  # the researcher's code raised (thread isolation): report it, keep running
            raise UavError(f"{what} raised {type(exc).__name__}: {shorten(str(exc), 500)}") from exc
        return answer
