"""A test-only output built from the parts docs/architecture.md ("Adding an output") lists, and nothing else: the
processor's ``getMark()`` gives a :class:`Mark` (its value type and reader), :class:`MarkRelay` turns it into an
effect while the controller has the :class:`Beats` capability, :data:`ENTRY` registers it, and
:func:`register` enters the method and the entry where the platform reads them."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import pytest

import processors.base
from processors.outputs import READERS, Reader, read_output
from uav_tui.relays import registry
from uav_tui.relays.contract import RelayParts, Unserved
from uav_tui.relays.registry import RelayEntry

if TYPE_CHECKING:
    from uav_tui.hosting.host import ProcessedFrame


@dataclass(frozen=True, slots=True)
class Mark:
    """The value type: a spot the processor wants marked, in frame pixels."""

    x: int
    y: int


def read_mark(value: object) -> Mark | None:
    """The reader: what ``getMark()`` returned, checked (TypeError: the frame's error, nothing is marked)."""
    return read_output(value, Mark, "getMark()", "a Mark or None")


@runtime_checkable
class Beats(Protocol):
    """The capability the output needs: a controller that says how old its heartbeat is (the simulated one has it)."""

    def heartbeat_age_s(self) -> float | None: ...


class MarkRelay:
    """The relay: each frame's mark is "sent" (kept in :attr:`marked`) while the heartbeat is fresh and autonomy on."""

    field = "mark"

    def __init__(self, parts: RelayParts) -> None:
        assert isinstance(parts.controller, Beats)
        self.controller = parts.controller
        self.gate = parts.gate
        self.marked: list[Mark] = []
        self.stops: list[str] = []
        self.closed = False
        parts.gate.stop_listeners.append(self.stop)

    def consider(self, result: ProcessedFrame) -> str:
        mark = result.outcome.outputs.get(self.field)
        if mark is None:
            return ""
        if not self.gate.enabled:
            return "not sent: autonomy off"
        self.marked.append(mark)
        return "sent"

    def stop(self, reason: str) -> None:
        self.stops.append(reason)

    async def close(self) -> None:
        self.closed = True

    @property
    def counts(self) -> dict[str, int]:
        return {"sent": len(self.marked)}


def say_unmarked(result: ProcessedFrame) -> str:
    """The stand-in's words on a frame with a mark, for a controller without :class:`Beats`."""
    return "" if result.outcome.outputs.get("mark") is None else "not sent: the flight controller has no heartbeat"


ENTRY = RelayEntry("mark", Beats, MarkRelay, lambda parts: Unserved("mark", say_unmarked))
"""The registry entry."""


def register(monkeypatch: pytest.MonkeyPatch) -> None:
    """Enter ``getMark`` where a real output is written into the source (the processor contract's optional methods
    and :data:`~processors.outputs.READERS`) and :data:`ENTRY` in the relays' registry, for one test."""
    monkeypatch.setattr(processors.base, "OPTIONAL_METHODS", (*processors.base.OPTIONAL_METHODS, "getMark"))
    monkeypatch.setattr(processors.base, "_SIGNATURES", (*processors.base._SIGNATURES, "getMark(self)"))
    monkeypatch.setitem(READERS, "getMark", Reader("mark", lambda processor: processor.getMark(), read_mark))
    monkeypatch.setattr(registry, "REGISTRY", [*registry.REGISTRY, ENTRY])
