"""The page in a real headless Chromium: video decodes, a drag / click / tap selects, F2 reaches the processor."""

from __future__ import annotations

import asyncio
import shutil
from pathlib import Path

import pytest

from tests.web.conftest import processor_of
from uav_tui.core import UavCore

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]

pytestmark = pytest.mark.skipif(not Path(CHROMIUM).exists(), reason="needs Debian's chromium (apt install chromium)")


async def wait_for(predicate, timeout: float = 10.0, what: str = "condition") -> None:
    deadline = asyncio.get_running_loop().time() + timeout
    while not predicate():
        if asyncio.get_running_loop().time() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        await asyncio.sleep(0.05)


async def picture_box(page) -> tuple[float, float, float, float]:
    """Where the 640x480 picture is on screen, computed here independently of the page's script."""
    box = await page.locator("#video").bounding_box()
    scale = min(box["width"] / 640, box["height"] / 480)
    w, h = 640 * scale, 480 * scale
    return box["x"] + (box["width"] - w) / 2, box["y"] + (box["height"] - h) / 2, w, h


def close_to(actual: tuple[int, ...], expected: tuple[int, ...], tolerance: int = 3) -> bool:
    return all(abs(a - e) <= tolerance for a, e in zip(actual, expected, strict=True))


async def test_page_streams_video_and_selects_targets(web_core: UavCore, tmp_path: Path) -> None:
    from playwright.async_api import async_playwright

    processor = processor_of(web_core)
    async with async_playwright() as pw:
        browser = await pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            context = await browser.new_context(viewport={"width": 1000, "height": 640}, has_touch=True)
            page = await context.new_page()
            response = await page.goto(web_core.web.url)
            assert response is not None and response.status == 200
            frames = "document.getElementById('video').getVideoPlaybackQuality().totalVideoFrames"
            await page.wait_for_function(f"{frames} > 10", timeout=60000)  # ICE + first keyframe: slow when loaded
            first = await page.evaluate(frames)
            await page.wait_for_function(f"{frames} > {first + 5}", timeout=10000)
            assert web_core.web.video.viewers == 1

            # a drag, on a wide viewport (letterbox left and right) and a tall one (top and bottom)
            for viewport in ({"width": 1000, "height": 640}, {"width": 420, "height": 900}):
                await page.set_viewport_size(viewport)
                await asyncio.sleep(0.2)
                x, y, w, h = await picture_box(page)
                count = len(processor.rois)
                assert w < viewport["width"] - 10 or h < viewport["height"] - 150  # really letterboxed
                await page.mouse.move(x + 0.25 * w, y + 0.30 * h)
                await page.mouse.down()
                await page.mouse.move(x + 0.45 * w, y + 0.50 * h, steps=4)
                await page.mouse.move(x + 0.55 * w, y + 0.70 * h, steps=4)
                await page.mouse.up()
                await wait_for(lambda c=count: len(processor.rois) > c, what="catch_cmd after a drag")
                assert close_to(processor.rois[-1], (160, 144, 192, 192)), processor.rois[-1]

            # a click selects a small box (a tenth of the shorter side) around the point
            x, y, w, h = await picture_box(page)
            shown = await page.locator("#events li").count()
            await page.evaluate("document.getElementById('reply').textContent = ''")
            await page.mouse.click(x + 0.5 * w, y + 0.5 * h)
            await wait_for(lambda: len(processor.rois) == 3, what="catch_cmd after a click")
            assert close_to(processor.rois[-1], (296, 216, 48, 48)), processor.rois[-1]
            # its reply and event reach the page, status pushes go on: the picture stays where the operator aims
            await page.wait_for_function(f"document.querySelectorAll('#events li').length > {shown}")
            await page.wait_for_function("document.getElementById('reply').textContent !== ''")
            await page.evaluate("document.getElementById('status').textContent += ' and a long line' .repeat(20)")
            assert await picture_box(page) == (x, y, w, h)

            # a finger tap does the same (pointer events)
            await page.touchscreen.tap(x + 0.75 * w, y + 0.25 * h)
            await wait_for(lambda: len(processor.rois) == 4, what="catch_cmd after a tap")
            assert close_to(processor.rois[-1], (456, 96, 48, 48)), processor.rois[-1]

            # a press in the letterbox (outside the picture) selects nothing
            await page.mouse.click(x + 0.5 * w, max(1, y - 20))
            await page.get_by_role("button", name="F2").click()
            await wait_for(lambda: processor.buttons == [2], what="customize_processing(2)")
            assert len(processor.rois) == 4
            origins = {e.origin for e in web_core.events.recent if e.kind == "command" and "roi" in e.message}
            assert origins == {"web:127.0.0.1"}

            await page.set_viewport_size({"width": 1000, "height": 640})
            await page.wait_for_function("document.getElementById('status').textContent.includes('watching')")
            # what the processor tracks (its box: the last ROI moved 10 px) is in the status and outlined
            await page.wait_for_function(
                "document.getElementById('status').textContent.includes('box 466,106 48x48')", timeout=5000)
            await asyncio.sleep(0.6)  # a status push after the resize: the outline follows the picture
            x, y, w, h = await picture_box(page)
            outline = await page.locator("#tracked").bounding_box()
            assert outline is not None
            expected = (x + 466 * w / 640, y + 106 * h / 480, 48 * w / 640, 48 * h / 480)
            assert close_to(tuple(round(v) for v in outline.values()), tuple(round(v) for v in expected)), outline
            await page.screenshot(path=str(tmp_path / "page.png"))
            shot = Path("/tmp/uav_web_page.png")
            shutil.copy(tmp_path / "page.png", shot)

            # a second viewer watches the same relayed track
            second = await context.new_page()
            await second.goto(web_core.web.url)
            await second.wait_for_function(f"{frames} > 5", timeout=20000)
            assert web_core.web.video.viewers == 2
            await page.close()
            await wait_for(lambda: web_core.web.video.viewers == 1, what="the first viewer to leave")
            assert web_core.web.video.source is not None
            await second.close()
            await wait_for(lambda: web_core.web.video.viewers == 0, what="the second viewer to leave")
            assert web_core.web.video.source is None  # no viewer: no listener, no conversion
            assert sum("viewer left" in e.message for e in web_core.events.recent) == 2

            # stopping the core with a viewer watching closes its peer connection
            third = await context.new_page()
            await third.goto(web_core.web.url)
            await third.wait_for_function(f"{frames} > 5", timeout=20000)
            await web_core.stop("test finished")
            assert not web_core.web.viewers.peers and web_core.web.video.source is None
        finally:
            await browser.close()
