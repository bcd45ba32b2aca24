"""What a processor host is to the platform (:class:`ProcessorHost`) and what it hands over: a processed frame, an
operator call's answer, the host's state."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING, Any, Protocol

from sources.buffer import Frame
from uav_tui.config import Isolation
from uav_tui.hosting.wire import FrameOutcome

if TYPE_CHECKING:
    from processors import LoadedProcessor
    from processors.base import ProcessorInfo
    from sources.buffer import FrameBuffer
    from uav_tui.flight.telemetry import TelemetryManager
    from uav_tui.stats import PipelineStats, RollingStats
    from uav_values.camera import CameraModel


@dataclass(frozen=True, slots=True)
class ProcessedFrame:
    """One frame's trip through the processor: the frame and its :class:`~uav_tui.hosting.wire.FrameOutcome` as the
    call made it (frozen: nothing after the call changes it; a replay's stage clock puts a re-timed copy here, the
    operator's lock on a track a copy with the track's box and vector). What the platform did with it is the core's
    :class:`~uav_tui.relays.contract.HandledFrame`."""

    frame: Frame
    """The frame as captured; the processor may have drawn its overlay on ``frame.image``."""
    outcome: FrameOutcome
    """What the processor did with it: stage times (monotonic ns), vector, outputs, box, detections, error."""


@dataclass(frozen=True, slots=True)
class Answer:
    """What an operator's call into the processor (``catch_cmd``, ``customize_processing``) returned, and when."""

    value: Any
    t_taken_ns: int
    """When the processor began the call (monotonic ns): the frames it started after that saw its effect."""


class HostState(StrEnum):
    """Where the processor's host is in its life."""

    STARTING = "starting"  # the first child is loading
    RUNNING = "running"  # a loaded child gets the frames
    RESTARTING = "restarting"  # the child died; a fresh one is started after a back-off
    CRASHED = "crashed"  # the child died (and, with a reason, the restarts gave up: the processor stays off)


@dataclass(frozen=True, slots=True)
class HostPhase:
    """The host's state with what it counts; ``str()`` reads ``running``, ``restarting 2``, ``crashed: reason``."""

    state: HostState
    restart: int = 0
    """The restart being waited for (1, 2, ...) while ``RESTARTING``, else 0."""
    reason: str = ""
    """Why the processor stays off, once ``CRASHED`` for good; "" otherwise."""

    def __str__(self) -> str:
        if self.state is HostState.RESTARTING:
            return f"{self.state} {self.restart}"
        if self.reason:
            return f"{self.state}: {self.reason}"
        return self.state.value


@dataclass(frozen=True, slots=True)
class ProcessorState:
    """How the processor's host is doing, for the status line, the TUI and the web page."""

    isolation: Isolation
    phase: HostPhase
    """Starting, running, restarting (and which restart) or crashed (and why it stays off)."""
    pid: int | None
    memory_mb: float | None
    """Resident memory of the processor's process (None in thread mode: it is the platform's)."""

    def summary(self) -> str:
        """``running, pid 4242, 38 MB``; ``restarting 2``; ``crashed: reason``; ``in a platform thread``."""
        if self.isolation is Isolation.THREAD:
            return "in a platform thread"
        parts = [str(self.phase)]
        if self.pid is not None:
            parts.append(f"pid {self.pid}")
        if self.memory_mb is not None:
            parts.append(f"{self.memory_mb:.0f} MB")
        return ", ".join(parts)


StageClock = Callable[[Frame, FrameOutcome], FrameOutcome]
"""A replay's clock: ``frame``'s outcome with its stage times moved onto the replay's clock."""


class DeliversResults:
    """What both hosts do with a frame's outcome, on the loop: its stage times moved onto a replay's clock
    (``stage_clock``), counted in ``stats`` (an error once, here), kept as ``last``, handed to the core."""

    stats: RollingStats
    stage_clock: StageClock | None
    last: ProcessedFrame | None
    consecutive_errors: int
    _on_result: Callable[[ProcessedFrame], None]

    def _deliver(self, frame: Frame, outcome: FrameOutcome) -> None:
        if self.stage_clock is not None:
            outcome = self.stage_clock(frame, outcome)
        self.stats.add(frame.seq, frame.t_mono_ns, outcome.t_start_ns, outcome.t_end_ns,
                       outcome.t_vector_ns or outcome.t_end_ns)
        if outcome.error is None:
            self.consecutive_errors = 0
        else:
            self.stats.errors += 1
            self.consecutive_errors += 1
        self.last = result = ProcessedFrame(frame, outcome)
        self._on_result(result)


class ProcessorHost(Protocol):
    """Runs one processor on the newest frame of a buffer: :class:`~uav_tui.hosting.thread_host.ThreadHost`
    (``isolation = "thread"``) and :class:`~uav_tui.hosting.process_host.SubprocessHost` (``"process"``)."""

    isolation: Isolation
    stats: RollingStats
    stage_clock: StageClock | None
    """Set in a replay: moves a result's stage times onto the replay's clock (before they are counted)."""
    current: Frame | None
    """The frame whose ``tmMgr.save`` calls are being stored (None between frames)."""
    last: ProcessedFrame | None
    """The newest processed frame."""
    consecutive_errors: int
    """Frames in a row on which the processor raised."""

    @property
    def saves_throttled(self) -> int:
        """``tmMgr.save`` calls dropped above ``save_max_hz``, wherever the processor runs."""

    @property
    def processor(self) -> LoadedProcessor:
        """What was loaded (``instance`` is None when it lives in another process)."""
        ...

    @property
    def busy_s(self) -> float:
        """Seconds the processor has been on its current frame or call (0 when idle)."""
        ...

    def bind_telemetry(self, telemetry: TelemetryManager) -> None:
        """Give the processor its ``tmMgr``: the telemetry at each frame's capture; ``telemetry`` stores saves."""
        ...

    def attach(self, buffer: FrameBuffer, camera: CameraModel | None = None) -> None:
        """Take frames from ``buffer`` from now on (a new source, with ``camera`` its model for ``tmMgr.camera()``)."""
        ...

    async def run(self) -> None:
        """Keep the processor running until cancelled; then stop it."""
        ...

    async def call(self, method: str, *args: Any) -> Answer:
        """Call ``processor.<method>(*args)`` between two frames; what it raised propagates."""
        ...

    async def reload(self) -> ProcessorInfo:
        """Load the processor's code as it is now and swap it in; a load error keeps the old one."""
        ...

    def snapshot(self) -> PipelineStats:
        """The pipeline's rates and stage times."""
        ...

    def state(self) -> ProcessorState:
        """How the host is doing."""
        ...

    def close(self) -> None:
        """Stop taking frames; idempotent."""
        ...
