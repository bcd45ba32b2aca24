"""The status panels on an 80-column terminal: what stays in view when a row is longer than the panel."""

from __future__ import annotations

import dataclasses
import time

import pytest
from rich.text import Text

from uav_tui.core import UavCore
from uav_tui.flight.geolocate import OK, GeoFix
from uav_tui.headless import format_status
from uav_tui.tui._algorithm import AlgorithmPanel
from uav_tui.tui._pipeline import PipelinePanel
from uav_tui.tui.app import UavApp

from .test_snapshots import FRAME, STATUS


@pytest.mark.parametrize(("uri", "size", "stalled", "row"), [
    # The README's USB camera with options: the device stays, the options give way to size and stall.
    ("usb:/dev/video2?width=1280&height=720&fps=30&fourcc=MJPG", (1280, 720), True,
     "cam  usb:/dev/video2… 1280x720 STALLED"),
    # A video file: its name stays.
    ("file:/home/pi/flights/2026-11-20/lake-crossing.mp4", (1920, 1080), False,
     "cam  file:…lake-crossing.mp4 1920x1080"),
    ("synthetic:?fps=30", (640, 480), False, "cam  synthetic:?fps=30 640x480"),
])
async def test_the_camera_row_keeps_frame_size_and_stall_in_view(make_config, uri, size, stalled, row):
    width, height = size
    source = {"width": width, "height": height, **({"stalled_since": time.time()} if stalled else {})}
    status = dataclasses.replace(STATUS, source_uri=uri, source=source)
    app = UavApp(UavCore(make_config()), status=lambda: status, frames=lambda: (1, FRAME, None))
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause(0.3)
        panel = app.query_one(PipelinePanel)
        assert panel.render_line(0).text.rstrip() == row


async def test_dropped_saves_are_counted_in_the_pipeline_panels_border(make_config):
    status = dataclasses.replace(STATUS, saves_dropped={"throttled": 38, "outside a frame": 2})
    app = UavApp(UavCore(make_config()), status=lambda: status, frames=lambda: (1, FRAME, None))
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause(0.3)
        panel = app.query_one(PipelinePanel)
        assert Text.from_markup(panel.border_subtitle).plain == "40 saves dropped (38 throttled, 2 outside a frame)"


@pytest.mark.parametrize("columns", [80, 100])
async def test_the_algorithm_panel_says_where_the_box_is_and_what_the_gimbal_does(make_config, columns):
    target = GeoFix(OK, 47.39781, 8.5456, 488.5, 0.64, 8.485, 8.485, 9.8, "home")
    telemetry = dataclasses.replace(STATUS.telemetry, gimbal_pitch_deg=-45.0, gimbal_yaw_deg=120.0)
    status = dataclasses.replace(STATUS, target=target, telemetry=telemetry, gimbal_sent=210, gimbal_controlled=True,
                                 capabilities=STATUS.capabilities | {"getGimbalPointing"})
    app = UavApp(UavCore(make_config()), status=lambda: status, frames=lambda: (1, FRAME, None))
    async with app.run_test(size=(columns, 24)) as pilot:
        await pilot.pause(0.3)
        panel = app.query_one(AlgorithmPanel)
        shown = panel.describe(status).plain  # whole rows: the panel cuts them at its edge
        rows = [panel.render_line(y).text.rstrip() for y in range(panel.size.height)]
    assert "box  300,200 120x90 @ 47.397810,8.545600 12 m at 045 deg +-0.6 m\n" in shown, shown
    assert rows[1].startswith("box  300,200 120x90 @ 47.3978"), rows
    # Whole on screen (#46; before: one "auto" row, cut before the gimbal at 80 and at 100 columns).
    assert rows[3:5] == ["auto 42 flown, 1 rejected", "gim  P-45 Y120 (controlled, 210 sent)"], rows


async def test_the_landing_targets_have_their_row_beside_the_gimbal(make_config):
    telemetry = dataclasses.replace(STATUS.telemetry, gimbal_pitch_deg=-90.0, gimbal_yaw_deg=0.0)
    status = dataclasses.replace(STATUS, telemetry=telemetry, precland=True, landing_targets_sent=120,
                                 capabilities=STATUS.capabilities | {"getLandingTarget"})
    app = UavApp(UavCore(make_config()), status=lambda: status, frames=lambda: (1, FRAME, None))
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause(0.3)
        panel = app.query_one(AlgorithmPanel)
        rows = [panel.render_line(y).text.rstrip() for y in range(panel.size.height)]
    assert rows[4] == "out  land ON, 120 sent; gim P-90 Y000", rows


async def test_the_algorithm_panel_says_why_there_is_no_landing_target(make_config):
    """Issue 47: the processor's own reason (or the relay's refusal), not only "no landing target yet"."""
    status = dataclasses.replace(STATUS, capabilities=STATUS.capabilities | {"getLandingTarget"},
                                 landing_none_reason="the processor says: 2 markers with id 7: which is the pad?")
    app = UavApp(UavCore(make_config()), status=lambda: status, frames=lambda: (1, FRAME, None))
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause(0.3)
        shown = app.query_one(AlgorithmPanel).describe(status).plain
    assert "land off, 0 sent, the processor says: 2 markers with id 7: which is the pad?\n" in shown, shown
    assert "(the processor says: 2 markers with id 7: which is the pad?)" in format_status(status, 1.0)
