"""``picam:0`` — a Raspberry Pi CSI camera (v1/v2/v3/HQ, NoIR included) through Picamera2.

Picamera2 comes with Raspberry Pi OS, not from PyPI wheels that work: it is imported only when a
``picam:`` source opens, so every other source works without it.

Channel order: libcamera names formats by their order in a 32-bit word, so Picamera2's
``"RGB888"`` is laid out B, G, R in memory and ``capture_array()`` returns it as a BGR array,
which is exactly what OpenCV and our processors expect. No conversion is done (or needed).
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from sources.base import CaptureSource
from sources.errors import SourceError
from sources.uri import SourceUri

logger = logging.getLogger(__name__)

PIXEL_FORMAT = "RGB888"
"""Picamera2 format whose arrays are BGR in memory (see the module docstring)."""

FRAME_TIMEOUT_S = 2.0
"""A camera that delivers nothing for this long (or three frame times) is stalled and gets reopened."""

INSTALL_HINT = ("picamera2 is not available: on Raspberry Pi OS run `sudo apt install python3-picamera2` and "
                "create the virtual environment with `python3 -m venv --system-site-packages .venv` so it can see "
                "the system package")


def _import_picamera2() -> Any:
    try:
        from picamera2 import Picamera2
    except ImportError as exc:  # also raised when libcamera's bindings are missing
        raise SourceError(f"{INSTALL_HINT} ({exc})") from exc
    return Picamera2


class PicamSource(CaptureSource):
    """A CSI camera: index, size, frame rate, optional NoIR tuning, exposure and gain.

    URI: ``picam:INDEX[?width=1280&height=720&fps=30&tuning=imx219_noir.json&exposure_us=8000&gain=2.0]``.
    ``tuning`` is a file name Picamera2 finds among the installed tuning files (or a path);
    ``exposure_us`` (ExposureTime) and ``gain`` (AnalogueGain) turn off the automatic exposure
    for what they set.
    """

    kind = "picam"

    def __init__(self, uri: str, index: int = 0, *, width: int = 640, height: int = 480, fps: float = 30.0,
                 tuning: str | None = None, exposure_us: int | None = None, gain: float | None = None) -> None:
        super().__init__(uri, f"camera {index}")
        self.index = index
        self.requested = (width, height, fps)
        self.tuning = tuning
        self.controls: dict[str, Any] = {}
        if exposure_us is not None:
            self.controls["ExposureTime"] = exposure_us
        if gain is not None:
            self.controls["AnalogueGain"] = gain
        self.sensor_model: str | None = None
        self._camera: Any = None
        self._frame_timeout_s = FRAME_TIMEOUT_S

    @classmethod
    def from_uri(cls, uri: SourceUri, **_context: Any) -> PicamSource:
        target = uri.target or "0"
        if not target.isdigit():
            raise SourceError(f"{uri.text!r}: give the camera index, e.g. picam:0 (picam:1 for the second camera)")
        source = cls(uri.text, int(target), width=uri.take_int("width", 640) or 640,
                     height=uri.take_int("height", 480) or 480, fps=uri.take_float("fps", 30.0) or 30.0,
                     tuning=uri.take_str("tuning"), exposure_us=uri.take_int("exposure_us"),
                     gain=uri.take_float("gain"))
        uri.finish()
        return source

    def _open_device(self) -> None:
        picamera2 = _import_picamera2()
        width, height, fps = self.requested
        tuning = picamera2.load_tuning_file(self.tuning) if self.tuning else None
        try:
            camera = picamera2(self.index, tuning=tuning)
        except (IndexError, RuntimeError) as exc:
            raise SourceError(f"CSI camera {self.index} cannot be opened ({exc}): is the ribbon cable seated, "
                              "the camera enabled, and no other program (rpicam-*, libcamera) using it?") from exc
        try:
            frame_us = int(round(1e6 / fps))
            config = camera.create_video_configuration(
                main={"size": (width, height), "format": PIXEL_FORMAT},
                controls={"FrameDurationLimits": (frame_us, frame_us), **self.controls},
                queue=False)  # capture_array waits for the next frame rather than handing out a queued one
            camera.configure(config)
            camera.start()
        except Exception:
            camera.close()
            raise
        self._camera = camera
        granted = camera.camera_configuration()
        self.width, self.height = granted["main"]["size"]
        limits = granted.get("controls", {}).get("FrameDurationLimits")
        self.fps = 1e6 / limits[0] if limits else fps
        self._frame_timeout_s = max(FRAME_TIMEOUT_S, 3 * self.controls.get("ExposureTime", 0) / 1e6, 3 / self.fps)
        self.sensor_model = camera.camera_properties.get("Model")

    def _grab(self) -> np.ndarray | None:
        # Asynchronous request + bounded wait: a camera that stops delivering becomes a stall
        # (and a reopen by the capture base) instead of a thread blocked forever.
        job = self._camera.capture_array("main", wait=False)
        try:
            frame: np.ndarray | None = self._camera.wait(job, timeout=self._frame_timeout_s)
            return frame
        except TimeoutError:
            return None

    def _close_device(self) -> None:
        camera, self._camera = self._camera, None
        if camera is not None:
            try:
                camera.stop()
            finally:
                camera.close()

    def _extra_properties(self) -> dict[str, Any]:
        width, height, fps = self.requested
        return {"index": self.index, "requested_width": width, "requested_height": height, "requested_fps": fps,
                "tuning": self.tuning, "controls": dict(self.controls), "sensor": self.sensor_model}
