"""The page, in a real headless Chromium, says where the tracked car is: position, distance and bearing."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from tests.core.flight_helpers import flying_core
from tests.web.conftest import TOKEN, free_port, make_core
from tests.web.test_page_browser import CHROMIUM, CHROMIUM_ARGS

pytestmark = pytest.mark.skipif(not Path(CHROMIUM).exists(), reason="needs Debian's chromium (apt install chromium)")

LOCATED = re.compile(r"^target (-?\d+\.\d{6}),(-?\d+\.\d{6}) (\d+) m at (\d{3}) deg \+-(\d+\.\d) m$")


async def target_line(url: str, wanted: str) -> tuple[str, str]:
    """The page's target line once it contains ``wanted``, and its class."""
    from playwright.async_api import async_playwright

    async with async_playwright() as pw:
        browser = await pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            page = await browser.new_page(viewport={"width": 1000, "height": 640})
            await page.goto(url)
            line = page.locator("#target")
            await line.filter(has_text=wanted).wait_for(state="visible", timeout=20000)
            return await line.text_content() or "", await line.get_attribute("class") or ""
        finally:
            await browser.close()


async def test_the_page_shows_where_the_car_is_from_20_m(tmp_path: Path) -> None:
    web = {"web": True, "web_host": "127.0.0.1", "web_port": free_port(), "web_token": TOKEN}
    source = "sim:?fps=15&targets=1&target_speed=0"  # a parked car 6 m north of home
    async with flying_core(tmp_path, altitude=20.0, source=source,
                           processor="tests.recording.recorder_processors:RedCar", **web) as core:
        text, kind = await target_line(core.web.url, " m at ")
        car_n, car_e, _ = core.source.targets[0].position(0.0)
        home = core.controller.sim.home
        vehicle = core.truth.latest()
    found = LOCATED.match(text)
    assert found, text
    lat, lon, distance, bearing, sigma = (float(v) for v in found.groups())
    north, east, _ = home.to_local(lat, lon, home.alt_m)
    assert math.hypot(north - car_n, east - car_e) <= 1.0, (north, east)
    # from the vehicle hovering over home: 6 m away, due north (a few degrees either side as it drifts)
    assert distance == pytest.approx(math.hypot(car_n - vehicle["n"], car_e - vehicle["e"]), abs=1.0)
    assert bearing <= 10 or bearing >= 350
    assert 0.1 <= sigma <= 2.0 and kind == "target"


async def test_the_page_says_why_a_box_is_not_located() -> None:
    core = make_core(camera_hfov=62.0)  # a camera model, but no vehicle: no GPS position
    await core.start()
    try:
        await core.execute("roi 100 100 50 50")
        text, kind = await target_line(core.web.url, "not located")
    finally:
        await core.stop("test finished")
    assert text == "target not located: no GPS position" and kind == "target warn"


DETECTED = re.compile(r"^#\d+ car (\d\.\d\d) (-?\d+\.\d{6}),(-?\d+\.\d{6}) (\d+) m at (\d{3}) deg \+-(\d+\.\d) m$")


async def test_the_page_lists_each_detection_where_it_is(tmp_path: Path) -> None:
    from playwright.async_api import async_playwright

    web = {"web": True, "web_host": "127.0.0.1", "web_port": free_port(), "web_token": TOKEN}
    source = "sim:?fps=15&targets=2&target_speed=0"  # two parked cars, both in view from 30 m
    async with flying_core(tmp_path, altitude=30.0, source=source,
                           processor="tests.recording.recorder_processors:RedCars", **web) as core:
        async with async_playwright() as pw:
            browser = await pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                page = await browser.new_page(viewport={"width": 1000, "height": 640})
                await page.goto(core.web.url)
                items = page.locator("#detections li")
                await items.nth(1).filter(has_text=" m at ").wait_for(state="visible", timeout=20000)
                texts = await items.all_text_contents()
            finally:
                await browser.close()
        cars = [target.position(0.0)[:2] for target in core.source.targets]
        home = core.controller.sim.home
    assert len(texts) == 2, texts
    scores = []
    for text in texts:
        found = DETECTED.match(text)
        assert found, text
        score, lat, lon = (float(v) for v in found.groups()[:3])
        north, east, _ = home.to_local(lat, lon, home.alt_m)
        assert min(math.hypot(north - n, east - e) for n, e in cars) <= 1.5, (text, cars)
        scores.append(score)
    assert scores == sorted(scores, reverse=True)  # the most confident first
    assert len({text.split()[0] for text in texts}) == 2, texts  # each its own track (issue 50)
