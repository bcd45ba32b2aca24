"""The pipeline panel: camera, processing rate and latency, skipped frames, recording."""

from __future__ import annotations

from rich.text import Text

from uav_tui.status import CoreStatus
from uav_tui.tui._panel import StatusPanel


class PipelinePanel(StatusPanel):
    """How frames flow: camera -> processor, and what is being recorded."""

    TITLE = "Pipeline"

    def describe(self, status: CoreStatus) -> Text:
        p, source = status.pipeline, status.source
        size = f"{source.get('width', 0)}x{source.get('height', 0)}"
        camera = Text(f"{status.source_uri} {size}")
        if source.get("stalled_since"):
            camera.append(" STALLED", self.get_component_rich_style("panel--bad"))
        age = Text(f"{p.frame_age_ms:.0f} ms")
        if p.busy_ms > 1000:
            age.append(f" busy {p.busy_ms / 1000:.1f} s", self.get_component_rich_style("panel--warn"))
        rows = [
            ("cam", camera),
            ("fps", f"cam {p.capture_fps:4.1f}  proc {p.processed_fps:4.1f}"),
            ("age", age),
            ("time", f"p50 {p.processing_ms_p50:.1f}  p95 {p.processing_ms_p95:.1f} ms"),
            ("skip", f"{p.frames_skipped} of {p.frames_processed + p.frames_skipped}"),
            ("rec", self._recording(status.recording)),
        ]
        if status.recording:
            rows.append(("run", str(status.recording.get("run_dir", "")).rstrip("/").rsplit("/", 1)[-1]))
        return self.rows(*rows)

    def _recording(self, recording: dict[str, object]) -> Text:
        if not recording:
            return Text("off")
        text = Text(f"on, {recording.get('frames_saved', 0)} frames saved")
        dropped = recording.get("dropped") or 0
        if dropped:
            text.append(f" {dropped} dropped", self.get_component_rich_style("panel--warn"))
        return text
