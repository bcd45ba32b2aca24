"""What both processor hosts hand the platform: a processed frame, an operator call's answer, the host's state."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from processors.base import Box
from sources.buffer import Frame


@dataclass(slots=True)
class ProcessedFrame:
    """One frame's trip through the processor, with the time of each stage (monotonic ns)."""

    frame: Frame
    """The frame as captured; the processor may have drawn its overlay on ``frame.image``."""
    t_start_ns: int
    t_end_ns: int = 0
    t_vector_ns: int = 0
    """When getPreparedVector returned (0 if the processor has none)."""
    vector: Any = None
    """What getPreparedVector returned, unchecked (the autonomy gate validates it)."""
    error: str | None = None
    """Traceback text if the processor raised."""
    decision: str = ""
    """What the autonomy gate did with the vector: ``executed`` or why not."""
    extra: dict[str, Any] = field(default_factory=dict)
    """Fields the processor stored with ``tmMgr.save(frame, **extra)`` for this frame."""
    saved: bool = False
    """True when the processor saved this frame's image."""
    box: Box | None = None
    """The processor's ``box`` attribute after this frame (what it tracks), or None."""


@dataclass(frozen=True, slots=True)
class Answer:
    """What an operator's call into the processor (``catch_cmd``, ``customize_processing``) returned, and when."""

    value: Any
    t_taken_ns: int
    """When the processor began the call (monotonic ns): the frames it started after that saw its effect."""


@dataclass(frozen=True, slots=True)
class ProcessorState:
    """How the processor's host is doing, for the status line, the TUI and the web page."""

    isolation: str
    """``process`` (its own process) or ``thread`` (a thread of the platform)."""
    state: str
    """``starting``, ``running``, ``restarting N`` or ``crashed: reason``."""
    pid: int | None
    memory_mb: float | None
    """Resident memory of the processor's process (None in thread mode: it is the platform's)."""

    def summary(self) -> str:
        """``running, pid 4242, 38 MB``; ``restarting 2``; ``crashed: reason``; ``in a platform thread``."""
        if self.isolation == "thread":
            return "in a platform thread"
        parts = [self.state]
        if self.pid is not None:
            parts.append(f"pid {self.pid}")
        if self.memory_mb is not None:
            parts.append(f"{self.memory_mb:.0f} MB")
        return ", ".join(parts)
