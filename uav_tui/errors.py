"""Errors raised by uav-tui.

Each plug-in level keeps its exception types beside its contract (:mod:`sources.errors`,
:mod:`processors.errors`, :mod:`controllers.errors`), and the camera model's is beside it in the value types
(:mod:`uav_values.camera`), so no level imports the platform. The platform adds its own and catches them all
together::

    UavError                     the platform's own
    └── ConfigError              bad configuration value or file (names the key)
        └── CommandError         an operator command that cannot be parsed
    sources.SourceError          a camera that cannot be opened or stopped delivering
    └── SourceUriError           a camera URI that cannot be parsed (a configuration error, key "source")
    uav_values.CameraModelError  a camera model that cannot be built (a calibration file, another frame size);
                                 a ValueError, so a configured file's is a ConfigError naming its key
    processors.ProcessorLoadError  a processor that cannot be loaded (a configuration error, key "processor")
    controllers.ControllerError  anything on the flight-controller side (ConnectError, CommandDenied,
                                 LinkLost, NotSupported, NoVehicle)

``except KNOWN_ERRORS`` catches every error raised on purpose, ``except CONFIG_ERRORS`` every
configuration mistake. Messages say what to do next. A rejected vector is an event, not an exception.
"""

from __future__ import annotations

from controllers.errors import CommandDenied, ConnectError, ControllerError, LinkLost, NotSupported, NoVehicle
from processors.errors import ProcessorLoadError
from sources.errors import SourceError, SourceUriError
from uav_values.camera import CameraModelError

__all__ = [
    "CONFIG_ERRORS", "KNOWN_ERRORS", "CameraModelError", "CommandDenied", "CommandError", "ConfigError", "ConnectError",
    "ControllerError", "LinkLost", "NoVehicle", "NotSupported", "ProcessorLoadError", "SourceError",
    "SourceUriError", "UavError", "error_line",
]


class UavError(Exception):
    """Root of the errors the platform itself raises on purpose."""


class ConfigError(UavError):
    """A configuration value or file is wrong; the message names the key."""

    def __init__(self, message: str, *, key: str | None = None) -> None:
        super().__init__(message)
        self.key = key


class CommandError(ConfigError):
    """An operator command (key, script line, web message) cannot be parsed."""


CONFIG_ERRORS: tuple[type[Exception], ...] = (ConfigError, SourceUriError, ProcessorLoadError)
"""Every configuration mistake, whichever level found it; each has ``.key``."""

KNOWN_ERRORS: tuple[type[Exception], ...] = (UavError, SourceError, CameraModelError, ProcessorLoadError,
                                              ControllerError)
"""Every error raised on purpose, by the platform or by a level."""


def error_line(message: object, prog: str = "uav-tui") -> str:
    """How every command-line error is printed: ``PROG: error: MESSAGE``, the way argparse prints its own."""
    return f"{prog}: error: {message}"
