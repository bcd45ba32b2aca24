"""How a vector ended: a kind the platform compares, and the text logs and the status have always shown."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum


class VectorEndKind(StrEnum):
    """The ways a vector ends."""

    NONE = "none"  # no vector has ended yet
    COMPLETED = "completed"  # its time ran out: zero, then the hold
    STOPPED = "stopped"  # an operator command or a stop cut it short
    FAILED = "failed"  # offboard was refused or a setpoint could not be sent
    LEFT_OFFBOARD = "left offboard"  # someone else (pilot, failsafe) changed the mode: abandoned, mode left alone


@dataclass(frozen=True)
class VectorEnd:
    """How the last vector ended; ``str()`` gives the text shown since these were strings.

    Attributes:
        kind: what ended it.
        detail: the error (``FAILED``) or the mode the vehicle is in now (``LEFT_OFFBOARD``), else empty.
    """

    kind: VectorEndKind = VectorEndKind.NONE
    detail: str = ""

    def __str__(self) -> str:
        if self.kind is VectorEndKind.NONE:
            return ""
        if self.kind is VectorEndKind.FAILED:
            return f"failed: {self.detail}"
        if self.kind is VectorEndKind.LEFT_OFFBOARD:
            return f"vehicle left offboard ({self.detail})"
        return self.kind.value
