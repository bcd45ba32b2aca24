"""``usb:0`` / ``usb:/dev/video2`` — a USB (UVC) camera read through OpenCV's V4L2 backend."""

from __future__ import annotations

import logging
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import cv2

from sources.errors import SourceError, SourceUriError
from sources.uri import SourceUri
from sources.videocapture import VideoCaptureSource

logger = logging.getLogger(__name__)

DEFAULT_FOURCC = "MJPG"
"""Compressed frames fit USB 2 bandwidth at 720p30 and above; ``fourcc=YUYV`` asks for raw frames."""

CaptureFactory = Callable[[str], cv2.VideoCapture]
"""Builds the capture object for a device path."""


def _open_v4l2(device: str) -> cv2.VideoCapture:
    return cv2.VideoCapture(device, cv2.CAP_V4L2)


class UsbSource(VideoCaptureSource):
    """A V4L2 camera with a one-frame driver buffer, reporting what the driver granted.

    URI: ``usb:INDEX|PATH[?width=W&height=H&fps=F&fourcc=MJPG]``. Width, height, fps and the pixel
    format are requests to the driver; ``get_properties()`` shows both the request and the grant.

    Args:
        capture_factory: builds the capture for the device path. The default opens it with V4L2;
            tests pass a factory reading a video file or a scripted capture in place of a camera.
    """

    kind = "usb"
    _resize_to_request = False

    def __init__(self, uri: str, device: str, *, width: int | None = None, height: int | None = None,
                 fps: float | None = None, fourcc: str | None = DEFAULT_FOURCC,
                 capture_factory: CaptureFactory = _open_v4l2) -> None:
        super().__init__(uri, device, width=width, height=height)
        self.requested_fps = fps
        self.requested_fourcc = fourcc
        self.fourcc = ""
        self.buffer_size: int | None = None
        self._capture_factory = capture_factory

    @classmethod
    def from_uri(cls, uri: SourceUri, *, capture_factory: CaptureFactory = _open_v4l2,
                 **_context: Any) -> UsbSource:
        target = uri.target or "0"
        device = f"/dev/video{target}" if target.isdigit() else target
        if not device.startswith("/"):
            raise SourceUriError(f"camera URI {uri.text!r}: give a device index or path, e.g. usb:0 or "
                                 "usb:/dev/video2", key="source")
        fourcc = uri.take_str("fourcc", DEFAULT_FOURCC)
        if fourcc is not None and len(fourcc) != 4:
            raise SourceUriError(f"camera URI {uri.text!r}: fourcc={fourcc!r} must be four characters, "
                                 "e.g. MJPG or YUYV", key="source")
        source = cls(uri.text, device, width=uri.take_int("width"), height=uri.take_int("height"),
                     fps=uri.take_float("fps"), fourcc=fourcc.upper() if fourcc else None,
                     capture_factory=capture_factory)
        uri.finish()
        return source

    def _new_capture(self) -> cv2.VideoCapture:
        check_device(self.device)
        return self._capture_factory(self.device)

    def _configure(self, capture: cv2.VideoCapture) -> None:
        # The pixel format first: it decides which sizes and rates the driver offers.
        if self.requested_fourcc:
            capture.set(cv2.CAP_PROP_FOURCC, cv2.VideoWriter.fourcc(*self.requested_fourcc))
        width, height = self.requested_size
        if width:
            capture.set(cv2.CAP_PROP_FRAME_WIDTH, width)
        if height:
            capture.set(cv2.CAP_PROP_FRAME_HEIGHT, height)
        if self.requested_fps:
            capture.set(cv2.CAP_PROP_FPS, self.requested_fps)
        capture.set(cv2.CAP_PROP_BUFFERSIZE, 1)  # keep the driver queue short: frames stay fresh
        self.fourcc = decode_fourcc(capture.get(cv2.CAP_PROP_FOURCC))
        self.buffer_size = int(capture.get(cv2.CAP_PROP_BUFFERSIZE)) or None

    def _open_device(self) -> None:
        super()._open_device()
        width, height = self.requested_size
        wanted = (width or self.width, height or self.height, self.requested_fps or self.fps)
        if wanted != (self.width, self.height, self.fps):
            logger.info("%r: asked for %sx%s @ %s fps, the driver granted %dx%d @ %.1f fps (%s)", self,
                        *wanted, self.width, self.height, self.fps, self.fourcc or "?")

    def _open_error(self) -> Exception:
        return _busy_error(self.device) or SourceError(
            f"{self.device} exists but cannot be opened as a camera (a metadata node? try the next index)")

    def _no_frame_error(self) -> Exception:
        return _busy_error(self.device) or SourceError(
            f"{self.device} opened but delivered no frame (unsupported format {self.requested_fourcc}? "
            "try fourcc=YUYV or a smaller size)")

    def _extra_properties(self) -> dict[str, Any]:
        return {**super()._extra_properties(), "requested_fps": self.requested_fps,
                "requested_fourcc": self.requested_fourcc, "fourcc": self.fourcc, "buffer_size": self.buffer_size}


def check_device(device: str) -> None:
    """Raise SourceError naming the problem if ``device`` is missing or not readable by this user."""
    path = Path(device)
    if not path.exists():
        present = sorted(str(p) for p in Path("/dev").glob("video*"))
        listing = ", ".join(present) if present else "none (is the camera plugged in? see `lsusb`)"
        raise SourceError(f"no such camera device {device}; video devices present: {listing}")
    if not os.access(path, os.R_OK | os.W_OK):
        raise SourceError(f"permission denied on {device}: add this user to the video group "
                          "(`sudo usermod -aG video $USER`), then log in again")


def device_holders(device: str) -> list[tuple[int, str]]:
    """(pid, command name) of every process with ``device`` open, from /proc/*/fd."""
    target = os.path.realpath(device)
    holders = []
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit():
            continue
        try:
            if any(os.readlink(fd) == target for fd in (proc / "fd").iterdir()):
                holders.append((int(proc.name), (proc / "comm").read_text().strip()))
        except OSError:  # the process ended, or it is not ours to inspect
            continue
    return holders


def _busy_error(device: str) -> SourceError | None:
    holders = device_holders(device)
    if not holders:
        return None
    who = ", ".join(f"PID {pid} ({'this process' if pid == os.getpid() else name})" for pid, name in holders)
    return SourceError(f"{device} is busy: held by {who}; stop that program or choose another camera")


def decode_fourcc(value: float) -> str:
    """The four characters of an OpenCV ``CAP_PROP_FOURCC`` value ('' when unknown)."""
    code = int(value)
    text = "".join(chr((code >> (8 * i)) & 0xFF) for i in range(4))
    return text if code and text.isprintable() else ""
