"""Letterboxing, half-block rendering and the cell -> frame-pixel mapping of the preview."""

from __future__ import annotations

import numpy as np
import pytest

from uav_tui.tui._cells import BOX_STYLE, TRACKED_STYLE, UPPER_HALF, Letterbox, render_cells


@pytest.mark.parametrize(("frame", "panel", "expected"), [
    ((640, 480), (40, 13), (2, 0, 35, 13)),    # 4:3 in a wide panel: bars left and right
    ((640, 480), (40, 40), (0, 12, 40, 15)),   # 4:3 in a tall panel: bars above and below
    ((1280, 720), (80, 24), (0, 1, 80, 22)),   # 16:9 (80 px wide -> 45 px -> 22.5 cells, rounded)
], ids=["4:3-wide-panel", "4:3-tall-panel", "16:9"])
def test_fit_keeps_aspect_and_centres(frame, panel, expected):
    box = Letterbox.fit(*frame, *panel)
    assert (box.x0, box.y0, box.width, box.height) == expected


def test_fit_caps_the_image_size_and_keeps_it_centred():
    box = Letterbox.fit(640, 480, 200, 60, max_cells=2400)  # would be 80x60 cells uncapped
    assert box.width * box.height <= 2400 and abs(box.width / (2 * box.height) - 4 / 3) < 0.05
    assert (box.x0, box.y0) == ((200 - box.width) // 2, (60 - box.height) // 2)


def test_roi_of_a_cell_box_covers_those_cells_in_frame_pixels():
    box = Letterbox.fit(640, 480, 40, 13)  # image at x0=2, 35x13 cells: 18.29 px per column, 36.92 px per row
    assert box.to_roi((2, 0, 36, 12)) == (0, 0, 640, 480)  # the whole image
    x, y, w, h = box.to_roi((12, 3, 21, 6))  # columns 10..19, rows 3..6 of the image
    assert (x, y) == (round(10 * 640 / 35), round(3 * 480 / 13))
    assert (x + w, y + h) == (round(20 * 640 / 35), round(7 * 480 / 13))
    assert box.to_roi((21, 6, 12, 3)) == (x, y, w, h)  # dragged up-left: same region


def test_roi_is_clamped_to_the_image_not_the_letterbox_bars():
    box = Letterbox.fit(640, 480, 40, 13)
    assert box.to_roi((0, 0, 39, 12)) == (0, 0, 640, 480)


def test_render_puts_top_pixel_in_foreground_and_bottom_in_background():
    image = np.zeros((4, 2, 3), np.uint8)
    image[0::2] = (255, 0, 0)  # BGR blue on even rows
    image[1::2] = (0, 0, 255)  # red on odd rows
    strips = render_cells(image, Letterbox.fit(2, 4, 2, 2))
    assert len(strips) == 2 and all(strip.cell_length == 2 for strip in strips)
    segment = list(strips[0])[0]
    assert segment.text == UPPER_HALF
    top, bottom = segment.style.color.triplet, segment.style.bgcolor.triplet
    assert max(top.red, top.green, bottom.green, bottom.blue) < 8  # colours are kept to 5 bits per channel
    assert top.blue >= 248 and bottom.red >= 248  # blue on top (foreground), red below (background)


def test_render_fills_the_panel_and_draws_the_selection_outline():
    image = np.full((480, 640, 3), 128, np.uint8)
    box = Letterbox.fit(640, 480, 40, 13)
    strips = render_cells(image, box, selection=(10, 2, 20, 8))
    assert len(strips) == 13 and all(strip.cell_length == 40 for strip in strips)
    cells = [[seg.style for seg in strip for _ in seg.text] for strip in strips]
    assert cells[2][10] == cells[2][20] == cells[8][15] == cells[5][10] == BOX_STYLE
    assert cells[5][15] != BOX_STYLE  # inside the box the image shows
    assert cells[5][0] is None  # letterbox bar: panel background


def test_the_processors_box_is_outlined_where_it_is_in_the_frame():
    image = np.full((480, 640, 3), 128, np.uint8)
    layout = Letterbox.fit(640, 480, 32, 12)  # no bars: 20 px per cell across, 40 px per cell down
    tracked = layout.cells_of((200, 120, 100, 160))
    assert tracked == (10, 3, 14, 6)
    assert layout.cells_of((630, 470, 50, 50)) == (31, 11, 31, 11)  # clamped to the image
    strips = render_cells(image, layout, selection=(2, 1, 4, 2), tracked=tracked)
    cells = [[seg.style for seg in strip for _ in seg.text] for strip in strips]
    col0, row0, col1, row1 = tracked
    assert cells[row0][col0] == cells[row1][col1] == cells[(row0 + row1) // 2][col0] == TRACKED_STYLE
    assert cells[(row0 + row1) // 2][(col0 + col1) // 2] != TRACKED_STYLE  # the target itself shows
    assert cells[1][2] == BOX_STYLE  # the operator's selection is drawn as well
