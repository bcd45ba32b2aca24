"""A stand-in for ``picamera2.Picamera2`` following the part of its real API that PicamSource uses.

It keeps real Picamera2's memory layout: libcamera's ``"RGB888"`` is B, G, R in memory (so
``capture_array`` gives a BGR array), ``"BGR888"`` is R, G, B. The scene is fixed: the left half
red, the right half blue, so a test can tell a correct channel order from a swapped one.
It is not a camera: it fails loudly when used out of order, as the real one does.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np

RED, BLUE = (255, 0, 0), (0, 0, 255)
"""Scene colours as (R, G, B)."""


class _Job:
    """Like picamera2's job: ``get_result(timeout)`` raises TimeoutError when nothing came in time."""

    def __init__(self, produce: Callable[[], np.ndarray | None]) -> None:
        self._produce = produce

    def get_result(self, timeout: float | None = None) -> np.ndarray:
        result = self._produce()
        if result is None:
            time.sleep(timeout or 0)
            raise TimeoutError
        return result


class Picamera2StandIn:
    """Stand-in for ``Picamera2(camera_num, tuning=None)``."""

    instances: ClassVar[list[Picamera2StandIn]] = []
    cameras: ClassVar[int] = 1
    frames_before_stall: ClassVar[list[int | None]] = []
    """Per instance in creation order: frames it delivers before going silent (None or absent: forever)."""

    def __init__(self, camera_num: int = 0, tuning: dict[str, Any] | None = None) -> None:
        if camera_num >= self.cameras:
            raise IndexError("list index out of range")  # what Picamera2 raises for a missing camera
        self.camera_num, self.tuning = camera_num, tuning
        self.camera_properties = {"Model": "imx219", "PixelArraySize": (3280, 2464)}
        self.config: dict[str, Any] | None = None
        self.controls: dict[str, Any] = {}
        self.started = False
        self.stop_calls = self.close_calls = 0
        plan = Picamera2StandIn.frames_before_stall
        self.frames_left = plan[len(self.instances)] if len(self.instances) < len(plan) else None
        Picamera2StandIn.instances.append(self)

    @staticmethod
    def load_tuning_file(tuning_file: str, dir: str | None = None) -> dict[str, Any]:  # noqa: A002 - real name
        return {"version": 2.0, "file": tuning_file}

    def create_video_configuration(self, main: dict[str, Any] | None = None, *, controls: dict[str, Any] | None = None,
                                   queue: bool = True, buffer_count: int = 6, **_: Any) -> dict[str, Any]:
        main = {"format": "XBGR8888", "size": (1280, 720), **(main or {})}
        return {"use_case": "video", "main": main, "controls": dict(controls or {}), "queue": queue,
                "buffer_count": buffer_count}

    def configure(self, config: dict[str, Any]) -> None:
        if self.started:
            raise RuntimeError("Camera must be stopped before configuring")
        width, height = config["main"]["size"]
        config["main"]["size"] = (width - width % 2, height - height % 2)  # libcamera aligns sizes
        self.config = config
        self.controls.update(config["controls"])

    def camera_configuration(self) -> dict[str, Any]:
        assert self.config is not None
        return self.config

    def set_controls(self, controls: dict[str, Any]) -> None:
        self.controls.update(controls)

    def start(self) -> None:
        if self.config is None:
            raise RuntimeError("Camera has not been configured")
        self.started = True

    def capture_array(self, name: str = "main", wait: bool | None = None) -> np.ndarray | _Job:
        """With ``wait=False`` returns a job for :meth:`wait`, as the real one does."""
        if not self.started:
            raise RuntimeError("Camera is not running")
        job = _Job(lambda: self._next_frame(name))
        return job if wait is False else job.get_result()

    def wait(self, job: _Job, timeout: float | None = None) -> np.ndarray:
        return job.get_result(timeout)

    def _next_frame(self, name: str) -> np.ndarray | None:
        if self.frames_left is not None:
            if self.frames_left <= 0:
                return None  # the sensor stopped delivering
            self.frames_left -= 1
        frame_us = self.controls.get("FrameDurationLimits", (33333, 33333))[0]
        time.sleep(frame_us / 1e6)  # the real call waits for the next frame
        assert self.config is not None
        stream = self.config[name]
        width, height = stream["size"]
        rgb = np.empty((height, width, 3), np.uint8)
        rgb[:, : width // 2], rgb[:, width // 2:] = RED, BLUE
        memory_order = {"RGB888": rgb[..., ::-1], "BGR888": rgb}[stream["format"]]
        return np.ascontiguousarray(memory_order)

    def stop(self) -> None:
        self.stop_calls += 1
        self.started = False

    def close(self) -> None:
        self.close_calls += 1
        self.started = False
