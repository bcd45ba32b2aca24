"""Choosing a region over the preview: mouse drag and keyboard box -> ``catch_cmd`` in frame pixels."""

from __future__ import annotations

import pytest

from uav_tui.flight.track_lock import LockState

from .conftest import HERE, started, wait_for

FRAME_W, FRAME_H = 640, 480


def image_area(cols: int, rows: int) -> tuple[int, int, int, int]:
    """Where a 640x480 frame lands in a cols x rows panel: x0, y0, width, height in cells (2 pixel rows/cell)."""
    scale = min(cols / FRAME_W, 2 * rows / FRAME_H)
    width, height = round(FRAME_W * scale), round(FRAME_H * scale / 2)
    return (cols - width) // 2, (rows - height) // 2, width, height


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
async def test_mouse_drag_selects_the_region_under_the_pointer(make_app, size):
    app = make_app()
    async with app.run_test(size=size) as pilot:
        await started(pilot)
        preview = app.query_one("#preview")
        await wait_for(pilot, lambda: preview.frames_drawn, what="the preview to draw")
        x0, y0, width, height = image_area(*preview.content_size)
        start, end = (x0 + 5, y0 + 2), (x0 + 14, y0 + 6)
        await pilot.mouse_down(preview, offset=start)
        await pilot.hover(preview, offset=(x0 + 9, y0 + 4))
        assert preview.selection == (*start, x0 + 9, y0 + 4)  # the box follows the pointer
        await pilot.hover(preview, offset=end)
        await pilot.mouse_up(preview, offset=end)
        processor = app.core.worker.processor.instance
        await wait_for(pilot, lambda: processor.rois, what="catch_cmd")
        left, top = round(5 * FRAME_W / width), round(2 * FRAME_H / height)
        right, bottom = round(15 * FRAME_W / width), round(7 * FRAME_H / height)
        assert processor.rois == [(left, top, right - left, bottom - top)]
        assert preview.selection is None


async def test_a_click_is_not_a_region(make_app):
    app = make_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        preview = app.query_one("#preview")
        await wait_for(pilot, lambda: preview.frames_drawn, what="the preview to draw")
        x0, y0, _, _ = image_area(*preview.content_size)
        await pilot.click(preview, offset=(x0 + 3, y0 + 3))
        await pilot.pause(0.3)
        assert app.core.worker.processor.instance.rois == []


async def test_a_click_inside_a_tracks_box_locks_it(make_app):
    app = make_app(processor=f"{HERE / 'procs.py'}:DetectingProcessor")
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        preview = app.query_one("#preview")
        await wait_for(pilot, lambda: preview.frames_drawn and app.core.lock.newest, what="the preview and a track")
        x0, y0, width, height = image_area(*preview.content_size)
        await pilot.click(preview, offset=(x0 + width * 3 // 4, y0 + height * 3 // 4))  # outside the car's box
        await pilot.pause(0.3)
        assert app.core.lock.state is LockState.OFF
        await pilot.click(preview, offset=(x0 + 3, y0 + 3))
        await wait_for(pilot, lambda: app.core.lock.state is LockState.LOCKED, what="the lock")
        assert app.core.lock.track_id == app.core.lock.newest[0].track_id
        assert app.core.worker.processor.instance.rois == []  # a click is no region


async def test_keyboard_box_moves_resizes_and_sends(make_app):
    app = make_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        preview = app.query_one("#preview")
        await wait_for(pilot, lambda: preview.frames_drawn, what="the preview to draw")
        await pilot.press("b")
        assert preview.keyboard and app.focused is preview
        c0, r0, c1, r1 = preview.selection
        await pilot.press("right", "right", "right", "shift+right", "shift+right", "down", "shift+down")
        assert preview.selection == (c0 + 3, r0 + 1, c1 + 5, r1 + 2)
        x0, y0, width, height = image_area(*preview.content_size)
        await pilot.press("enter")
        processor = app.core.worker.processor.instance
        await wait_for(pilot, lambda: processor.rois, what="catch_cmd")
        left, top = round((c0 + 3 - x0) * FRAME_W / width), round((r0 + 1 - y0) * FRAME_H / height)
        right = round((c1 + 6 - x0) * FRAME_W / width)
        bottom = round((r1 + 3 - y0) * FRAME_H / height)
        assert processor.rois == [(left, top, right - left, bottom - top)]
        assert not preview.keyboard and preview.selection is None


async def test_keyboard_box_escape_cancels_and_arrows_stay_inside_the_image(make_app):
    app = make_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        preview = app.query_one("#preview")
        await wait_for(pilot, lambda: preview.frames_drawn, what="the preview to draw")
        await pilot.press("b", *["left"] * 20, *["up"] * 8)
        x0, y0, _, _ = image_area(*preview.content_size)
        assert preview.selection[:2] == (x0, y0)
        await pilot.press("escape")
        await pilot.pause(0.2)
        assert preview.selection is None and not preview.keyboard
        assert app.core.worker.processor.instance.rois == []
