"""picam: Picamera2 configured right, BGR frames, controls passed through, a clean close.

``Picamera2`` is replaced at the import by ``Picamera2StandIn`` (tests/sources/picamera2_standin.py).
"""

from __future__ import annotations

import sys

import pytest

from sources import create_source, open_source
from uav_tui.errors import SourceError


def test_frames_are_bgr(picamera2_standin) -> None:
    source = open_source("picam:0?width=64&height=48&fps=60")
    try:
        frame = source.buffer.wait_newer(0, timeout=5)
        assert frame is not None and frame.image.shape == (48, 64, 3)
        assert frame.image[10, 5].tolist() == [0, 0, 255]  # left half of the scene is red: BGR (0, 0, 255)
        assert frame.image[10, 60].tolist() == [255, 0, 0]  # right half is blue
    finally:
        source.close()


def test_configuration_size_rate_tuning_and_controls(picamera2_standin) -> None:
    source = open_source("picam:0?width=1281&height=720&fps=25&tuning=imx219_noir.json&exposure_us=8000&gain=2.5")
    try:
        camera = picamera2_standin.instances[-1]
        assert camera.tuning == {"version": 2.0, "file": "imx219_noir.json"}
        assert camera.config["main"]["format"] == "RGB888" and camera.config["queue"] is False
        assert camera.controls == {"FrameDurationLimits": (40000, 40000), "ExposureTime": 8000, "AnalogueGain": 2.5}
        props = source.get_properties()
        assert (props["width"], props["height"]) == (1280, 720)  # granted (aligned) size, not the request
        assert props["requested_width"] == 1281
        assert props["fps"] == pytest.approx(25) and props["sensor"] == "imx219"
        assert props["controls"] == {"ExposureTime": 8000, "AnalogueGain": 2.5}
    finally:
        source.close()


def test_close_stops_and_closes_the_camera_once(picamera2_standin) -> None:
    source = open_source("picam:0?width=32&height=24&fps=100")
    assert source.buffer.wait_newer(1, timeout=5) is not None
    source.close()
    source.close()
    camera = picamera2_standin.instances[-1]
    assert (camera.stop_calls, camera.close_calls, camera.started) == (1, 1, False)


def test_a_silent_camera_is_a_stall_and_gets_reopened(picamera2_standin, fast_retry, monkeypatch) -> None:
    monkeypatch.setattr("sources.picam.FRAME_TIMEOUT_S", 0.2)
    picamera2_standin.frames_before_stall = [5]  # the first camera goes silent after 5 frames; the next is fine
    source = open_source("picam:0?width=32&height=24&fps=100")
    try:
        frame = source.buffer.wait_newer(5, timeout=10)
        assert frame is not None, source.get_properties()
        props = source.get_properties()
        assert props["stalled_since"] is None and "no frame" in props["last_error"]
        first, second = picamera2_standin.instances[:2]
        assert (first.stop_calls, first.close_calls) == (1, 1) and second.started
    finally:
        source.close()


def test_missing_camera_index(picamera2_standin) -> None:
    source = create_source("picam:3")
    assert source.open() is False
    assert "CSI camera 3 cannot be opened" in source.get_properties()["last_error"]


def test_without_picamera2_the_error_says_how_to_install_it(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "picamera2", None)  # makes the import fail, as off a Pi
    with pytest.raises(SourceError, match=r"sudo apt install python3-picamera2.*--system-site-packages"):
        open_source("picam:0")
