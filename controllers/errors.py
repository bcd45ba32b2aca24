"""Errors on the flight-controller side. Messages say what to do next.

::

    ControllerError          anything on the flight-controller side
    ├── ConnectError         bad connection string, no such port, no heartbeat
    ├── CommandDenied        the autopilot answered a command with a refusal (.result)
    ├── LinkLost             the heartbeat stopped
    ├── NotSupported         the autopilot does not implement the command
    └── NoVehicle            no flight controller is configured (``--fc none``)
"""

from __future__ import annotations

import traceback
from pathlib import Path

MAX_FAILURE_KINDS = 64
"""Kinds of failure a handler remembers; a traceback is logged for each new kind until there are this many."""


class ControllerError(Exception):
    """Anything that went wrong on the flight-controller side."""


class ConnectError(ControllerError):
    """The connection string is wrong, the port is missing or busy, or no heartbeat arrived."""


class CommandDenied(ControllerError):
    """The autopilot refused a command; ``result`` holds its answer (DENIED, BUSY, TIMEOUT, ...)."""

    def __init__(self, message: str, *, command: str = "", result: str = "") -> None:
        super().__init__(message)
        self.command = command
        self.result = result


class LinkLost(ControllerError):
    """The autopilot's heartbeat stopped."""


class NotSupported(ControllerError):
    """The autopilot does not implement this command."""


class NoVehicle(ControllerError):
    """No flight controller is configured, so commands that move a vehicle cannot run."""


class FailureKinds:
    """The kinds of unexpected failure a handler has logged: the first of each kind gets its traceback, once."""

    def __init__(self) -> None:
        self._seen: set[str] = set()

    def first(self, exc: BaseException) -> str | None:
        """``exc``'s kind (``ValueError at landing.py:72``: its type and the innermost line that raised it) when it
        is the first of its kind and there is room to remember it, else None."""
        frames = traceback.extract_tb(exc.__traceback__)
        kind = type(exc).__name__ + (f" at {Path(frames[-1].filename).name}:{frames[-1].lineno}" if frames else "")
        if kind in self._seen or len(self._seen) >= MAX_FAILURE_KINDS:
            return None
        self._seen.add(kind)
        return kind
