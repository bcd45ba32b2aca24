"""Route MAVSDK's own log lines into Python logging (it prints to stdout otherwise, over the TUI)."""

from __future__ import annotations

import logging

from mavsdk.logging import LogLevel, log_subscribe

logger = logging.getLogger("mavsdk")

LEVELS = {
    LogLevel.DEBUG: logging.DEBUG,
    LogLevel.INFO: logging.INFO,
    LogLevel.WARN: logging.WARNING,
    LogLevel.ERROR: logging.ERROR,
}

_routed = False


def _forward(level: LogLevel, message: str, file: str | None, line: int) -> bool:
    logger.log(LEVELS.get(level, logging.INFO), "%s", message)
    return True  # handled: MAVSDK does not print it


def route_mavsdk_log() -> None:
    """Install the forwarder once per process (MAVSDK's log subscription is global)."""
    global _routed
    if not _routed:
        log_subscribe(_forward)
        _routed = True
