"""The base for sources read through OpenCV's ``VideoCapture`` (files, USB cameras, network streams)."""

from __future__ import annotations

from typing import Any

import cv2
import numpy as np

from sources.base import CaptureSource


class VideoCaptureSource(CaptureSource):
    """Opens ``self._capture_target`` with ``self._backend``, optionally resizing frames.

    Subclasses set the target/backend, may tune the capture in ``_configure`` and may override
    ``_read_frame`` (to loop a file, say).
    """

    _backend = cv2.CAP_ANY

    def __init__(self, uri: str, device: str, *, width: int | None = None, height: int | None = None) -> None:
        super().__init__(uri, device)
        self.requested_size = (width, height)
        self._capture: cv2.VideoCapture | None = None

    @property
    def _capture_target(self) -> str | int:
        return self.device

    def _open_device(self) -> None:
        capture = cv2.VideoCapture(self._capture_target, self._backend)
        if not capture.isOpened():
            capture.release()
            raise self._open_error()
        self._capture = capture
        self._configure(capture)
        self.fps = float(capture.get(cv2.CAP_PROP_FPS) or 0.0)
        self.width = int(capture.get(cv2.CAP_PROP_FRAME_WIDTH))
        self.height = int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT))
        width, height = self.requested_size
        if width or height:
            self.width, self.height = _fit_size(self.width, self.height, width, height)

    def _configure(self, capture: cv2.VideoCapture) -> None:
        """Adjust the freshly opened capture; nothing by default."""

    def _open_error(self) -> Exception:
        raise NotImplementedError

    def _grab(self) -> np.ndarray | None:
        image = self._read_frame()
        if image is None:
            return None
        if image.shape[1] != self.width or image.shape[0] != self.height:
            image = cv2.resize(image, (self.width, self.height), interpolation=cv2.INTER_AREA)
        return image

    def _read_frame(self) -> np.ndarray | None:
        assert self._capture is not None
        ok, image = self._capture.read()
        return image if ok else None

    def _close_device(self) -> None:
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
