"""Fixtures shared by the processor tests."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from controllers.base import Telemetry


class FakeTelemetryManager:
    """Stands in for the platform's TelemetryManager: a fixed snapshot, and saves recorded in a list."""

    def __init__(self, **telemetry: Any) -> None:
        self.telemetry = Telemetry(**telemetry)
        self.saved: list[tuple[np.ndarray, dict[str, Any]]] = []

    def snapshot(self) -> Telemetry:
        return self.telemetry

    def save(self, frame: np.ndarray, **extra: Any) -> None:
        self.saved.append((frame.copy(), extra))


@pytest.fixture
def tm_mgr() -> FakeTelemetryManager:
    return FakeTelemetryManager(rel_alt_m=20.0)
