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
