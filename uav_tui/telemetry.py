"""Placeholder until the fc branch lands: TelemetryManager without a controller."""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from controllers.base import Telemetry

logger = logging.getLogger(__name__)


class TelemetryManager:
    def __init__(self, controller: Any = None) -> None:
        self.controller = controller
        self.saver: Callable[[Any, dict[str, Any]], None] | None = None
        self._latest = Telemetry()
        self._listeners: list[Callable[[Telemetry], None]] = []

    async def run(self) -> None:
        return None

    def snapshot(self) -> Telemetry:
        return self._latest

    def add_listener(self, cb: Callable[[Telemetry], None]) -> None:
        self._listeners.append(cb)

    def link_alive(self, max_age_s: float) -> bool:
        return False

    def save(self, frame: Any, **extra: Any) -> None:
        if self.saver is not None:
            self.saver(frame, extra)
