"""The pipeline panel: camera, processing rate and latency, skipped frames, recording."""

from __future__ import annotations

from rich.text import Text

from uav_tui.status import CoreStatus, saves_dropped_text
from uav_tui.tui._panel import StatusPanel

MIN_URI = 12
"""Characters of the camera's URI kept when its size and state need the room (an 80-column terminal)."""


def short_uri(uri: str, width: int) -> str:
    """``uri`` in at most ``width`` characters. Its options (after ``?``) go first, as the device or address
    before them says which camera it is; else what follows the scheme gives way to the end (a file's name)."""
    if len(uri) <= width:
        return uri
    if len(uri.partition("?")[0]) <= width - 1:
        return f"{uri[:width - 1]}…"
    scheme = uri.partition(":")[0] + ":"
    head = scheme if len(scheme) <= width // 2 else ""
    return f"{head}…{uri[len(uri) - (width - 1 - len(head)):]}"


class PipelinePanel(StatusPanel):
    """How frames flow: camera -> processor, and what is being recorded.

    Where the camera row is too narrow, its URI is shortened (:func:`short_uri`) so that the frame size and
    ``STALLED`` stay in view. ``tmMgr.save`` calls that were dropped are counted in the bottom border.
    """

    TITLE = "Pipeline"

    def describe(self, status: CoreStatus) -> Text:
        p = status.pipeline
        age = Text(f"{p.frame_age_ms:.0f} ms")
        if p.busy_ms > 1000:
            age.append(f" busy {p.busy_ms / 1000:.1f} s", self.get_component_rich_style("panel--warn"))
        rows: list[tuple[str, Text | str]] = [
            ("fps", f"cam {p.capture_fps:4.1f}  proc {p.processed_fps:4.1f}  skip {p.frames_skipped}"),
            ("age", age),
            ("time", f"p50 {p.processing_ms_p50:.1f}  p95 {p.processing_ms_p95:.1f} ms"),
            ("rec", self._recording(status.recording)),
        ]
        if status.recording:
            rows.append(("run", str(status.recording.get("run_dir", "")).rstrip("/").rsplit("/", 1)[-1]))
        # In the bottom border: the panel's height is fixed (app.tcss), and the rows above fill it.
        self.border_subtitle = self.styled(saves_dropped_text(status.saves_dropped), "warn")
        rows.insert(0, ("cam", self._camera(status, ["cam", *(label for label, _ in rows)])))
        return self.rows(*rows)

    def _camera(self, status: CoreStatus, labels: list[str]) -> Text:
        """URI, frame size and ``STALLED``; the URI shortened where the row is too narrow for all of it."""
        state = Text(f" {status.source.get('width', 0)}x{status.source.get('height', 0)}")
        if status.source.get("stalled_since"):
            state.append(" STALLED", self.get_component_rich_style("panel--bad"))
        room = self.room_before(state, labels, MIN_URI)
        return Text(status.source_uri if room is None else short_uri(status.source_uri, room)).append_text(state)

    def _recording(self, recording: dict[str, object]) -> Text:
        if not recording:
            return Text("off")
        text = Text(f"on, {recording.get('frames_saved', 0)} frames saved")
        dropped = recording.get("dropped") or 0
        if dropped:
            text.append(f" {dropped} dropped", self.get_component_rich_style("panel--warn"))
        return text
