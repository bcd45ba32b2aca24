"""The live preview: the newest processed frame in half-blocks, and ROI selection over it."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import psutil
from rich.segment import Segment
from textual import events
from textual.binding import Binding
from textual.message import Message
from textual.reactive import reactive
from textual.strip import Strip
from textual.widget import Widget

from uav_tui.tui._cells import Box, Letterbox, render_cells

logger = logging.getLogger(__name__)

FrameProvider = Callable[[], "tuple[int, np.ndarray, tuple[int, int, int, int] | None] | None"]
"""Returns ``(frame id, BGR image, the processor's box)`` of the newest processed frame, or None before the first."""

PREVIEW_FPS = 4.0
"""How often the preview redraws at most; the terminal, not the camera, sets how much is worth drawing."""

MAX_CELLS = 1600
"""Largest image drawn (about 64x25 cells for 4:3): every cell costs the loop time in Textual's compositor."""

CPU_BUDGET = 0.05
"""Largest share of one core the conversion may use: a big terminal on a slow board redraws less often."""

BUSY_CPU_PERCENT = 90.0
"""When the whole machine is this busy, the preview slows to :data:`BUSY_FPS`: the processor needs the CPU."""

BUSY_FPS = 1.0


MOVE_KEYS = Binding.Group("move box, shift+arrows: resize")


class FramePreview(Widget, can_focus=True):
    """Draws the newest processed frame, letterboxed, at :data:`PREVIEW_FPS` while it is on screen.

    The processor's ``box`` for that frame (what it tracks) is outlined in green.

    It draws less often when converting a frame costs more than :data:`CPU_BUDGET` of a core, or when
    the machine is saturated (:data:`BUSY_CPU_PERCENT`): the processor comes first.

    Drag with the mouse over the image, or press ``b`` for a keyboard box (arrows move, shift+arrows
    resize, Enter sends, Escape cancels), to choose a region; it is posted as :class:`RoiSelected`
    in frame pixels.
    """

    DEFAULT_CSS = """
    FramePreview { width: 1fr; height: 1fr; }
    FramePreview.-selecting { background: $boost; }
    """

    BINDINGS = [
        Binding("left", "move(-1, 0)", "Move", group=MOVE_KEYS),
        Binding("right", "move(1, 0)", "Move", group=MOVE_KEYS),
        Binding("up", "move(0, -1)", "Move", group=MOVE_KEYS),
        Binding("down", "move(0, 1)", "Move", group=MOVE_KEYS),
        Binding("shift+left", "grow(-1, 0)", "Resize", show=False),
        Binding("shift+right", "grow(1, 0)", "Resize", show=False),
        Binding("shift+up", "grow(0, -1)", "Resize", show=False),
        Binding("shift+down", "grow(0, 1)", "Resize", show=False),
        Binding("enter", "send_box", "Send ROI"),
        Binding("escape", "cancel_box", "Cancel"),
    ]

    selection: reactive[Box | None] = reactive(None, always_update=True)
    """The cell box being chosen (mouse drag or keyboard), drawn over the image."""
    keyboard: reactive[bool] = reactive(False, bindings=True)
    """True while the keyboard box is active (arrows, Enter, Escape belong to it)."""

    class RoiSelected(Message):
        """The operator chose a region: ``roi`` is (x, y, w, h) in frame pixels."""

        def __init__(self, roi: tuple[int, int, int, int]) -> None:
            super().__init__()
            self.roi = roi

    class PointClicked(Message):
        """The operator clicked (no drag) at ``x``, ``y`` in frame pixels."""

        def __init__(self, x: float, y: float) -> None:
            super().__init__()
            self.x, self.y = x, y

    def __init__(self, frames: FrameProvider, *, fps: float | None = None, id: str | None = None) -> None:
        super().__init__(id=id)
        self._frames = frames
        self._fps = fps or PREVIEW_FPS
        self._strips: list[Strip] = []
        self._drawn: tuple[object, ...] | None = None  # what _strips show: frame id, size, selection
        self._layout: Letterbox | None = None
        self._drag_start: tuple[int, int] | None = None
        self._next_draw = 0.0
        self._cpu_times: Any = None
        self.frames_drawn = 0
        """How many frames were converted to cells (for the benchmark and tests)."""

    def on_mount(self) -> None:
        self.set_interval(1 / self._fps, self.redraw)

    # -- drawing ---------------------------------------------------------------------------------

    def redraw(self, force: bool = False) -> None:
        """Convert the newest frame to cells if it, the panel size or the selection changed."""
        if not (self.is_on_screen and self.display) and not force:
            return
        newest = self._frames()
        cols, rows = self.content_size
        if newest is None or cols < 2 or rows < 1:
            self._layout, self._drawn = None, None
            self._strips = []
            self.refresh()
            return
        frame_id, image, tracked = newest
        key = (frame_id, cols, rows, self.selection, tracked)
        if key == self._drawn:
            return
        now = time.monotonic()
        if now < self._next_draw and not force:
            return
        height, width = image.shape[:2]
        layout = self._layout
        if layout is None or (layout.frame_w, layout.frame_h, layout.cols, layout.rows) != (width, height, cols, rows):
            layout = Letterbox.fit(width, height, cols, rows, MAX_CELLS)
        self._strips = render_cells(image, layout, self.selection, tracked and layout.cells_of(tracked))
        interval = (time.monotonic() - now) / CPU_BUDGET
        if self._machine_busy_percent() >= BUSY_CPU_PERCENT:
            interval = max(interval, 1 / BUSY_FPS)
        self._next_draw = now + interval - 0.5 / self._fps  # the timer's period is the floor; half a tick slack
        self._layout, self._drawn = layout, key
        self.frames_drawn += 1
        self.refresh()

    def _machine_busy_percent(self) -> float:
        """How busy all cores were since the previous call (from /proc/stat via psutil; cheap)."""
        times = psutil.cpu_times()
        previous, self._cpu_times = self._cpu_times, times
        if previous is None:
            return 0.0
        total = sum(times) - sum(previous)
        idle = (times.idle + getattr(times, "iowait", 0.0)) - (previous.idle + getattr(previous, "iowait", 0.0))
        return 100.0 * (1.0 - idle / total) if total > 0 else 0.0

    def render_line(self, y: int) -> Strip:
        if y < len(self._strips):
            return self._strips[y]
        width = self.content_size.width
        if y == self.content_size.height // 2 and not self._strips:
            text = "waiting for the first processed frame"[:width]
            return Strip([Segment(text.center(width))], width)
        return Strip.blank(width)

    def on_resize(self) -> None:
        self.redraw(force=True)

    def watch_selection(self) -> None:
        self.redraw(force=True)

    # -- mouse ROI -------------------------------------------------------------------------------

    def on_mouse_down(self, event: events.MouseDown) -> None:
        if self._layout is None or event.button != 1 or not self._layout.contains(event.x, event.y):
            return
        self.keyboard = False
        self._drag_start = (event.x, event.y)
        self.capture_mouse()
        self.selection = (event.x, event.y, event.x, event.y)

    def on_mouse_move(self, event: events.MouseMove) -> None:
        if self._drag_start is not None and self._layout is not None:
            col, row = self._layout.clamp_cell(event.x, event.y)
            self.selection = (*self._drag_start, col, row)

    def on_mouse_up(self, event: events.MouseUp) -> None:
        if self._drag_start is None or self._layout is None:
            return
        self.release_mouse()
        start, self._drag_start = self._drag_start, None
        end = self._layout.clamp_cell(event.x, event.y)
        self.selection = None
        if end != start:
            self.post_message(self.RoiSelected(self._layout.to_roi((*start, *end))))
        else:  # a plain click is not a region: it may lock the track under it
            x, y, w, h = self._layout.to_roi((*end, *end))
            self.post_message(self.PointClicked(x + w / 2, y + h / 2))

    # -- keyboard ROI ----------------------------------------------------------------------------

    def start_keyboard_box(self) -> bool:
        """Show a box in the middle of the image and give the arrows to it; False without a frame."""
        if self._layout is None:
            return False
        self.selection = self._layout.centre_box()
        self.keyboard = True
        self.add_class("-selecting")
        self.focus()
        return True

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action in ("move", "grow", "send_box", "cancel_box"):
            return self.keyboard
        return True

    def action_move(self, dx: int, dy: int) -> None:
        if self.selection is None or self._layout is None:
            return
        c0, r0, c1, r1 = self.selection
        lay = self._layout
        dx = max(lay.x0 - c0, min(dx, lay.x0 + lay.width - 1 - c1))
        dy = max(lay.y0 - r0, min(dy, lay.y0 + lay.height - 1 - r1))
        self.selection = (c0 + dx, r0 + dy, c1 + dx, r1 + dy)

    def action_grow(self, dx: int, dy: int) -> None:
        if self.selection is None or self._layout is None:
            return
        c0, r0, c1, r1 = self.selection
        c1, r1 = self._layout.clamp_cell(max(c0 + 1, c1 + dx), max(r0, r1 + dy))
        self.selection = (c0, r0, c1, r1)

    def action_send_box(self) -> None:
        if self.selection is not None and self._layout is not None:
            self.post_message(self.RoiSelected(self._layout.to_roi(self.selection)))
        self.action_cancel_box()

    def on_blur(self) -> None:
        if self.keyboard:  # focus went elsewhere: the arrows no longer move the box, so drop it
            self.action_cancel_box()

    def action_cancel_box(self) -> None:
        self.keyboard = False
        self.selection = None
        self.remove_class("-selecting")
        if self.has_focus:
            self.screen.set_focus(None)
