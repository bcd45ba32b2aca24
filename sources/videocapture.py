"""The base for sources read through OpenCV's ``VideoCapture`` (files, USB cameras, network streams)."""

from __future__ import annotations

from typing import Any

import cv2
import numpy as np

from sources.base import CaptureSource
from sources.errors import SourceError


class VideoCaptureSource(CaptureSource):
    """Opens ``self._capture_target`` with ``self._backend`` and confirms it with a first frame.

    The size reported is the size of the frames actually decoded. When a width/height was asked
    for and ``_resize_to_request`` is true, frames are resized to it; a source that can ask the
    device itself (USB) sets it false and reports what the device granted instead.

    Subclasses set the target/backend, may tune the capture in ``_configure``, may build the
    capture differently in ``_new_capture`` (open options, a test stand-in) and may override
    ``_read_frame`` (to loop a file, say).
    """

    _backend = cv2.CAP_ANY
    _resize_to_request = True
    """Resize frames to the requested size (False: ask the device and report what it granted)."""

    def __init__(self, uri: str, device: str, *, width: int | None = None, height: int | None = None) -> None:
        super().__init__(uri, device)
        self.requested_size = (width, height)
        self._capture: cv2.VideoCapture | None = None
        self._first: np.ndarray | None = None

    @property
    def _capture_target(self) -> str | int:
        return self.device

    def _new_capture(self) -> cv2.VideoCapture:
        return cv2.VideoCapture(self._capture_target, self._backend)

    def _open_device(self) -> None:
        capture = self._new_capture()
        if not capture.isOpened():
            capture.release()
            raise self._open_error()
        self._capture = capture
        self._configure(capture)
        ok, first = capture.read()
        if not ok or first is None:
            self._close_device()
            raise self._no_frame_error()
        self._first = first
        self.fps = float(capture.get(cv2.CAP_PROP_FPS) or 0.0)
        self.height, self.width = int(first.shape[0]), int(first.shape[1])
        width, height = self.requested_size
        if self._resize_to_request and (width or height):
            self.width, self.height = _fit_size(self.width, self.height, width, height)

    def _configure(self, capture: cv2.VideoCapture) -> None:
        """Adjust the freshly opened capture; nothing by default."""

    def _open_error(self) -> Exception:
        return SourceError(f"{self.device}: cannot be opened")

    def _no_frame_error(self) -> Exception:
        return SourceError(f"{self.device}: opened but delivered no frame")

    def _grab(self) -> np.ndarray | None:
        image, self._first = self._first, None
        if image is None:
            image = self._read_frame()
        if image is None:
            return None
        if image.shape[1] != self.width or image.shape[0] != self.height:
            image = cv2.resize(image, (self.width, self.height), interpolation=cv2.INTER_AREA)
        return image

    def _read_frame(self) -> np.ndarray | None:
        assert self._capture is not None
        ok, image = self._capture.read(self._target())
        return image if ok else None

    def _target(self) -> np.ndarray | None:
        """The array the reader wants the next frame decoded into (None: OpenCV allocates one)."""
        return self.buffer.new_image((self.height, self.width, 3)) if self.width and self.height else None

    def _close_device(self) -> None:
        self._first = None
        if self._capture is not None:
            self._capture.release()
            self._capture = None

    def _extra_properties(self) -> dict[str, Any]:
        width, height = self.requested_size
        return {"requested_width": width, "requested_height": height}


def _fit_size(width: int, height: int, want_w: int | None, want_h: int | None) -> tuple[int, int]:
    """The requested size; a missing side keeps the aspect ratio."""
    if want_w and want_h:
        return want_w, want_h
    if want_w:
        return want_w, max(1, round(height * want_w / width))
    assert want_h
    return max(1, round(width * want_h / height)), want_h
