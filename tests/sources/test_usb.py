"""usb: URI parsing, device errors, granted-vs-requested, and reconnecting after a failure.

There is no V4L2 camera here: the VideoCapture path is exercised through ``UsbSource`` itself with
its ``capture_factory`` seam, reading a generated video file or a scripted capture object.
"""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from sources import create_source
from sources.uri import SourceUri
from sources.usb import UsbSource, check_device, decode_fourcc, device_holders
from uav_tui.errors import SourceError, SourceUriError


def _file_capture(device: str) -> cv2.VideoCapture:
    """Reads the 'device' (a video file) through FFmpeg in place of V4L2."""
    return cv2.VideoCapture(device, cv2.CAP_FFMPEG)


class ScriptedCapture:
    """Mimics the cv2.VideoCapture calls UsbSource makes: delivers ``frames`` frames, then fails."""

    def __init__(self, opened: bool = True, frames: int | None = None) -> None:
        self.opened, self.remaining = opened, frames
        self.props: dict[int, float] = {cv2.CAP_PROP_FPS: 30.0}
        self.released = False

    def isOpened(self) -> bool:  # noqa: N802 - OpenCV's name
        return self.opened

    def set(self, prop: int, value: float) -> bool:
        self.props[prop] = value
        return True

    def get(self, prop: int) -> float:
        return self.props.get(prop, 0.0)

    def read(self, image: np.ndarray | None = None) -> tuple[bool, np.ndarray | None]:
        if self.remaining is not None:
            if self.remaining <= 0:
                return False, None
            self.remaining -= 1
        time.sleep(0.005)
        if image is None or image.shape != (48, 64, 3):
            return True, np.full((48, 64, 3), 7, np.uint8)
        image[:] = 7  # as OpenCV does: decoded into the array it was given
        return True, image

    def release(self) -> None:
        self.released = True


def test_uri_index_and_path() -> None:
    by_index = create_source("usb:0")
    assert isinstance(by_index, UsbSource) and by_index.device == "/dev/video0"
    assert create_source("usb:").device == "/dev/video0"
    by_path = create_source("usb:/dev/video2?width=1280&height=720&fps=30&fourcc=yuyv")
    assert by_path.device == "/dev/video2"
    props = by_path.get_properties()
    assert (props["requested_width"], props["requested_height"], props["requested_fps"]) == (1280, 720, 30)
    assert props["requested_fourcc"] == "YUYV"
    assert create_source("usb:1").get_properties()["requested_fourcc"] == "MJPG"


@pytest.mark.parametrize("uri, message", [("usb:0?fourcc=MJPEG", "four characters"), ("usb:video0", "index or path"),
                                          ("usb:0?widht=640", "widht"), ("usb:0?fps=fast", "fps")],
                         ids=["fourcc", "relative", "typo", "fps"])
def test_uri_errors_name_the_problem(uri: str, message: str) -> None:
    with pytest.raises(SourceUriError, match=message):
        create_source(uri)


def test_missing_device_lists_the_video_devices_present(tmp_path: Path) -> None:
    with pytest.raises(SourceError, match=r"no such camera device /dev/video97; video devices present: "):
        check_device("/dev/video97")
    source = create_source("usb:97")
    assert source.open() is False
    assert "no such camera device /dev/video97" in source.get_properties()["last_error"]


def test_permission_problem_points_at_the_video_group(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    device = tmp_path / "video0"
    device.touch()
    monkeypatch.setattr("sources.usb.os.access", lambda path, mode: False)  # root passes every real check
    with pytest.raises(SourceError, match="permission denied .* video group"):
        check_device(str(device))


def test_busy_device_names_the_process_holding_it(tmp_path: Path) -> None:
    device = tmp_path / "video0"
    device.touch()
    holder = subprocess.Popen([sys.executable, "-c", f"f = open({str(device)!r}); import time; time.sleep(30)"])
    try:
        deadline = time.monotonic() + 10
        while holder.pid not in [pid for pid, _ in device_holders(str(device))] and time.monotonic() < deadline:
            time.sleep(0.05)
        source = UsbSource("usb:test", str(device), capture_factory=lambda _: ScriptedCapture(opened=False))
        assert source.open() is False
        error = source.get_properties()["last_error"]
        assert f"is busy: held by PID {holder.pid} (python" in error
    finally:
        holder.kill()
        holder.wait()


def test_reads_frames_and_reports_granted_vs_requested(video_file) -> None:
    clip = video_file(width=160, height=120, fps=15)
    source = UsbSource.from_uri(SourceUri.parse(f"usb:{clip}?width=1280&height=720&fps=60"),
                                capture_factory=_file_capture)
    try:
        assert source.open(), source.get_properties()["last_error"]
        frame = source.buffer.wait_newer(0, timeout=5)
        assert frame is not None and frame.image.shape == (120, 160, 3)  # the grant, not resized to the request
        props = source.get_properties()
        assert (props["width"], props["height"], props["fps"]) == (160, 120, 15)
        assert (props["requested_width"], props["requested_height"], props["requested_fps"]) == (1280, 720, 60)
        assert props["requested_fourcc"] == "MJPG" and props["fourcc"] != "MJPG"  # a file cannot switch codecs
    finally:
        source.close()


def test_recovers_after_read_failures_and_failed_reopens(fast_retry: None) -> None:
    script = [ScriptedCapture(frames=5), ScriptedCapture(opened=False), ScriptedCapture(opened=False),
              ScriptedCapture()]
    handed_out: list[ScriptedCapture] = []
    stalled = threading.Event()

    def factory(device: str) -> ScriptedCapture:
        if len(handed_out) == 1:
            stalled.set()
        handed_out.append(script[min(len(handed_out), len(script) - 1)])
        return handed_out[-1]

    source = UsbSource("usb:0", "/dev/null", capture_factory=factory)
    try:
        assert source.open()
        assert stalled.wait(5)
        assert source.get_properties()["stalled_since"] is not None
        assert source.buffer.wait_newer(10, timeout=10) is not None, source.get_properties()
        props = source.get_properties()
        assert props["stalled_since"] is None
        assert props["errors"] >= 3 and "reopen attempt" in props["last_error"]
        assert handed_out[0].released
    finally:
        source.close()
    assert handed_out[-1].released


def test_decode_fourcc() -> None:
    assert decode_fourcc(cv2.VideoWriter.fourcc(*"MJPG")) == "MJPG"
    assert decode_fourcc(0) == ""
