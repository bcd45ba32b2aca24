"""The flight recorder: one folder per run with telemetry, frames, events and run.json (see dataset.py)."""

from __future__ import annotations

from uav_tui.recording.recorder import NotRecording, Recorder
from uav_tui.recording.rows import EVENT_COLUMNS, FRAME_COLUMNS, TELEMETRY_COLUMNS, image_name
from uav_tui.recording.run_info import describe

__all__ = ["EVENT_COLUMNS", "FRAME_COLUMNS", "NotRecording", "TELEMETRY_COLUMNS", "Recorder", "describe", "image_name"]
