"""Errors raised by uav-tui.

The hierarchy, so callers catch at the level they care about::

    UavError
    ├── ConfigError              bad configuration value or file (names the key)
    │   ├── SourceUriError       a camera URI that cannot be parsed
    │   ├── ProcessorLoadError   a processor that cannot be imported or validated (.path, .class_name, .missing)
    │   └── CommandError         an operator command that cannot be parsed
    ├── SourceError              a camera that cannot be opened or stopped delivering
    └── ControllerError          anything on the flight-controller side
        ├── ConnectError         bad connection string, no such port, no heartbeat
        ├── CommandDenied        the autopilot answered a command with a refusal (.result)
        ├── LinkLost             the heartbeat stopped
        ├── NotSupported         the autopilot does not implement the command
        └── NoVehicle            no flight controller is configured (``--fc none``)

Messages say what to do next. A rejected vector is an event, not an exception.
"""

from __future__ import annotations


class UavError(Exception):
    """Root of every error uav-tui raises on purpose."""


class ConfigError(UavError):
    """A configuration value or file is wrong; the message names the key."""

    def __init__(self, message: str, *, key: str | None = None) -> None:
        super().__init__(message)
        self.key = key


class SourceUriError(ConfigError):
    """A camera URI cannot be parsed or names an unknown scheme."""


class CommandError(ConfigError):
    """An operator command (key, script line, web message) cannot be parsed."""


class ProcessorLoadError(ConfigError):
    """A processor cannot be loaded.

    Attributes:
        path: the file (or module) the processor came from, when known.
        class_name: the class that was asked for.
        missing: what is missing (a module, a class, a required method), when that is the cause.
    """

    def __init__(
        self,
        message: str,
        *,
        path: str | None = None,
        class_name: str | None = None,
        missing: str | None = None,
    ) -> None:
        super().__init__(message, key="processor")
        self.path = path
        self.class_name = class_name
        self.missing = missing


class SourceError(UavError):
    """A camera cannot be opened, or it stopped delivering frames."""


class ControllerError(UavError):
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
