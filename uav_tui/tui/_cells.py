"""Frames in terminal cells: letterboxing, half-block rendering and cell <-> frame-pixel mapping.

A terminal cell shows two image rows with the upper-half block ``▀``: its foreground colour is the
top pixel, its background the bottom one. A panel of ``cols x rows`` cells is therefore a canvas of
``cols x 2*rows`` pixels, into which the frame is fitted keeping its aspect ratio (letterbox).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from rich.color import Color
from rich.segment import Segment
from rich.style import Style
from textual.strip import Strip

UPPER_HALF = "\u2580"
"""``▀``: in every standard terminal font."""

BOX_CELL = "\u2588"
"""``█``: the ROI rectangle is drawn with full blocks, visible even without colours."""

BOX_STYLE = Style(color="yellow")
"""The ROI rectangle's colour."""

TRACKED_STYLE = Style(color="green")
"""The colour of the processor's ``box`` (what it tracks)."""

QUANT_MASK = 0xF8
"""Colours are kept to 5 bits per channel (invisible at preview size), so cells share cached styles."""

STYLE_CACHE = 65536
"""Most (top, bottom) colour pairs kept; the cache is emptied when full."""

Box = tuple[int, int, int, int]
"""A rectangle of cells: (col0, row0, col1, row1), inclusive, in panel coordinates."""


@dataclass(frozen=True, slots=True)
class Letterbox:
    """Where a ``frame_w x frame_h`` frame lands in a ``cols x rows`` cell panel.

    The image covers cells ``x0 .. x0+width-1`` and ``y0 .. y0+height-1``; each image cell is
    ``frame_w / width`` frame pixels wide and ``frame_h / height`` frame pixels tall.
    """

    frame_w: int
    frame_h: int
    cols: int
    rows: int
    x0: int
    y0: int
    width: int
    height: int

    @classmethod
    def fit(cls, frame_w: int, frame_h: int, cols: int, rows: int, max_cells: int = 0) -> Letterbox:
        """Fit the frame into the panel (2 pixel rows per cell), centred, aspect ratio kept.

        Args:
            max_cells: if > 0, the image covers at most this many cells (it is centred, smaller).
        """
        scale = min(cols / frame_w, 2 * rows / frame_h) if frame_w and frame_h else 0.0
        if max_cells and frame_w * frame_h * scale * scale / 2 > max_cells:
            scale = math.sqrt(2 * max_cells / (frame_w * frame_h))
        width = max(1, min(cols, round(frame_w * scale)))
        height = max(1, min(rows, round(frame_h * scale / 2)))
        return cls(frame_w, frame_h, cols, rows, (cols - width) // 2, (rows - height) // 2, width, height)

    def clamp_cell(self, col: int, row: int) -> tuple[int, int]:
        """The image cell nearest to panel cell (col, row)."""
        return (min(max(col, self.x0), self.x0 + self.width - 1),
                min(max(row, self.y0), self.y0 + self.height - 1))

    def contains(self, col: int, row: int) -> bool:
        return self.x0 <= col < self.x0 + self.width and self.y0 <= row < self.y0 + self.height

    def to_roi(self, box: Box) -> tuple[int, int, int, int]:
        """Frame-pixel ROI ``(x, y, w, h)`` covered by a cell box (both corner cells included)."""
        col0, row0, col1, row1 = box
        col0, row0 = self.clamp_cell(min(col0, col1), min(row0, row1))
        col1, row1 = self.clamp_cell(max(box[0], box[2]), max(box[1], box[3]))
        sx, sy = self.frame_w / self.width, self.frame_h / self.height
        x0, y0 = round((col0 - self.x0) * sx), round((row0 - self.y0) * sy)
        x1 = min(self.frame_w, round((col1 - self.x0 + 1) * sx))
        y1 = min(self.frame_h, round((row1 - self.y0 + 1) * sy))
        return x0, y0, x1 - x0, y1 - y0

    def cells_of(self, roi: tuple[int, int, int, int]) -> Box:
        """The cell box covering a frame-pixel ``(x, y, w, h)`` (clamped to the image)."""
        x, y, w, h = roi
        sx, sy = self.width / self.frame_w, self.height / self.frame_h
        col0, row0 = self.clamp_cell(self.x0 + math.floor(x * sx), self.y0 + math.floor(y * sy))
        col1, row1 = self.clamp_cell(self.x0 + math.ceil((x + w) * sx) - 1, self.y0 + math.ceil((y + h) * sy) - 1)
        return col0, row0, max(col0, col1), max(row0, row1)

    def centre_box(self, fraction: float = 0.25) -> Box:
        """A box in the middle of the image, ``fraction`` of its size: where keyboard ROI starts."""
        w, h = max(2, round(self.width * fraction)), max(1, round(self.height * fraction))
        col0, row0 = self.x0 + (self.width - w) // 2, self.y0 + (self.height - h) // 2
        return col0, row0, col0 + w - 1, row0 + h - 1


def render_cells(image: np.ndarray, box: Letterbox, selection: Box | None = None,
                 tracked: Box | None = None) -> list[Strip]:
    """Draw a BGR frame as half-block strips of ``box.cols x box.rows`` cells.

    Args:
        image: BGR uint8 frame (H x W x 3), or grey (H x W).
        box: where the image goes (``Letterbox.fit`` of this frame and panel).
        selection: a cell box to draw as a rectangle over the image (the ROI being chosen).
        tracked: a cell box to draw in :data:`TRACKED_STYLE` (the processor's ``box``), under the selection.

    Returns:
        One strip per cell row. Letterbox bars are blank cells in the panel's own background.
    """
    small: np.ndarray = cv2.resize(image, (box.width, box.height * 2), interpolation=cv2.INTER_AREA)
    if small.ndim == 2:
        small = cv2.cvtColor(small, cv2.COLOR_GRAY2BGR)
    small = (small & QUANT_MASK) | (~QUANT_MASK & 0xFF) // 2  # 5 bits per channel, centred in its step
    packed = (small[..., 2].astype(np.uint32) << 16) | (small[..., 1].astype(np.uint32) << 8) | small[..., 0]
    top, bottom = packed[0::2].tolist(), packed[1::2].tolist()
    outlines = [(edges, style) for edges, style in ((_box_edges(selection, box) if selection else {}, BOX_STYLE),
                                                    (_box_edges(tracked, box) if tracked else {}, TRACKED_STYLE))
                if edges]
    left = Segment(" " * box.x0) if box.x0 else None
    right_width = box.cols - box.x0 - box.width
    right = Segment(" " * right_width) if right_width > 0 else None
    blank = Strip([Segment(" " * box.cols)], box.cols)
    strips = [blank] * box.y0
    for r in range(box.height):
        segments = [left] if left else []
        marks = [(edges.get(box.y0 + r, ()), style) for edges, style in outlines]
        for c, (t, b) in enumerate(zip(top[r], bottom[r], strict=True)):
            style = next((style for marked, style in marks if box.x0 + c in marked), None)
            if style is not None:
                segments.append(Segment(BOX_CELL, style))
            else:
                segments.append(Segment(UPPER_HALF, _style(t, b)))
        if right:
            segments.append(right)
        strips.append(Strip(segments, box.cols))
    strips.extend([blank] * (box.rows - len(strips)))
    return strips


_colors: dict[int, Color] = {}
_styles: dict[int, Style] = {}


def _style(top: int, bottom: int) -> Style:
    """The cell style for two packed 0xRRGGBB colours, cached: building a rich Color costs ~10 us."""
    key = top << 24 | bottom
    style = _styles.get(key)
    if style is None:
        if len(_styles) >= STYLE_CACHE:
            _styles.clear()
        style = _styles[key] = Style.from_color(_color(top), _color(bottom))
    return style


def _color(packed: int) -> Color:
    color = _colors.get(packed)
    if color is None:
        color = _colors[packed] = Color.from_rgb(packed >> 16, (packed >> 8) & 255, packed & 255)
    return color


def _box_edges(selection: Box, box: Letterbox) -> dict[int, set[int]]:
    """Row -> columns of the selection's outline, clamped to the image."""
    col0, row0 = box.clamp_cell(min(selection[0], selection[2]), min(selection[1], selection[3]))
    col1, row1 = box.clamp_cell(max(selection[0], selection[2]), max(selection[1], selection[3]))
    edges = {row: {col0, col1} for row in range(row0, row1 + 1)}
    edges[row0] = edges[row1] = set(range(col0, col1 + 1))
    return edges
