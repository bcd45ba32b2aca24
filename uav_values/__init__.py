"""The value types every level shares (telemetry, a frame's snapshot); this package imports only the standard
library and NumPy, so processors, sources, controllers and the platform may all import it."""

from __future__ import annotations

from uav_values.telemetry import RECEIVE_STAMPS, TELEMETRY_FIELDS, PoseSample, Snapshot, Telemetry

__all__ = ["RECEIVE_STAMPS", "TELEMETRY_FIELDS", "PoseSample", "Snapshot", "Telemetry"]
