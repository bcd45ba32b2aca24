"""uav-tui: camera -> your algorithm -> flight controller, with an operator dashboard.

The names integrators use are listed in ``__all__`` and imported lazily on first use, so that
``sources``, ``processors`` and ``controllers`` can import ``uav_tui.errors`` without loading the core.
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "UavCore": "uav_tui.core",
    "CoreStatus": "uav_tui.status",
    "Config": "uav_tui.config",
    "load_config": "uav_tui.config",
    "Command": "uav_tui.flight.commands",
    "parse_command": "uav_tui.flight.commands:parse",
    "TelemetryManager": "uav_tui.flight.telemetry",
    "ProcessedFrame": "uav_tui.hosting.host",
    "HandledFrame": "uav_tui.relays.contract",
    "Event": "uav_tui.events",
    "UavError": "uav_tui.errors",
    "ConfigError": "uav_tui.errors",
    "ProcessorLoadError": "uav_tui.errors",
    "SourceError": "uav_tui.errors",
    "ControllerError": "uav_tui.errors",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    target = _EXPORTS.get(name)
    if target is None:
        raise AttributeError(f"module 'uav_tui' has no attribute {name!r}")
    module_name, _, attribute = target.partition(":")
    value = getattr(importlib.import_module(module_name), attribute or name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return __all__
