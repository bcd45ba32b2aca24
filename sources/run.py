"""``run:RUN[?speed=1|4|max]`` — the camera of a recorded run: its video, stamped with the recorded capture times.

Frames come from the run's ``video.ts`` in the order of its index ``video.csv`` (frames dropped while
recording are absent there too). A run recorded before the video existed has only the frames its
processor saved (``frames/``): they are played instead, and ``get_properties()["content"]`` says so.

Pacing: with the ``replay:`` flight controller of the same run, the controller's timeline decides
(the platform hands it over as ``timeline``); alone, frames come at their recorded times divided
by ``speed``, or with ``speed=max`` one at a time as fast as the reader takes them (lockstep).
"""

from __future__ import annotations

import csv
import json
import logging
import threading
import time
from collections.abc import Generator, Iterator
from pathlib import Path
from typing import Any, Protocol

import cv2
import numpy as np

from sources.base import CaptureSource
from sources.errors import SourceError
from sources.uri import SourceUri
from uav_values.camera import CameraModel

logger = logging.getLogger(__name__)

VIDEO_FILE = "video.ts"
INDEX_FILE = "video.csv"


class Timeline(Protocol):
    """What the source needs from a replay timeline (``controllers.replay_timeline.ReplayTimeline``)."""

    def show(self, t_ns: int, stop: threading.Event) -> bool: ...
    def finish(self, stop: threading.Event) -> None: ...


def recorded_frames(run_dir: Path) -> tuple[str, list[tuple[int, int, str]]]:
    """What a run can show: (``video`` or ``saved frames``, [(t_mono_ns, t_wall_ns, image file or "")])."""
    if (run_dir / VIDEO_FILE).is_file() and (run_dir / INDEX_FILE).is_file():
        rows = _rows(run_dir / INDEX_FILE)
        return "video", [(int(r["t_mono_ns"]), int(r["t_wall_ns"]), "") for r in rows if r["video_frame"]]
    rows = _rows(run_dir / "frames.csv") if (run_dir / "frames.csv").is_file() else []
    return "saved frames", [(int(r["t_mono_ns"]), int(r["t_wall_ns"]), r["image"]) for r in rows if r.get("image")]


def read_video(path: Path) -> Generator[np.ndarray, None, None]:
    """The frames of a recorded ``video.ts`` as BGR images, converted back the way the recorder converted them."""
    import av

    with av.open(str(path)) as container:
        for frame in container.decode(video=0):
            if frame.format.name == "yuv420p" and frame.width % 2 == 0 and frame.height % 2 == 0:
                yield cv2.cvtColor(frame.to_ndarray(format="yuv420p"), cv2.COLOR_YUV2BGR_I420)
            else:
                yield frame.to_ndarray(format="bgr24")


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


class RunSource(CaptureSource):
    """Plays a recorded run's camera once (it does not loop); ``finished`` is set after the last frame."""

    kind = "run"

    def __init__(self, uri: str, run_dir: str, *, speed: float | None = 1.0, timeline: Timeline | None = None) -> None:
        super().__init__(uri, str(Path(run_dir).expanduser()))
        self.run_dir = Path(self.device)
        self.speed = speed
        self.timeline = timeline
        self.content = ""
        self.finished = threading.Event()
        """Set once the last recorded frame was handed out."""
        self.shown = 0
        self._frames: list[tuple[int, int, str]] = []
        self._images: Generator[np.ndarray, None, None] | None = None
        self._times: tuple[int, int] | None = None
        self._started: tuple[int, int] | None = None  # (first recorded t, real monotonic t) when paced alone

    @classmethod
    def from_uri(cls, uri: SourceUri, *, timeline: Timeline | None = None, **_context: Any) -> RunSource:
        if not uri.target:
            raise SourceError(f"{uri.text!r}: give the run folder, e.g. run:runs/2026-05-01T10-00-00Z")
        text = uri.take_str("speed", "1") or "1"
        try:
            speed = None if text.strip().lower() == "max" else float(text)
        except ValueError:
            speed = -1.0
        if speed is not None and not speed > 0:
            raise SourceError(f"{uri.text!r}: speed must be a positive number or max, got {text!r}")
        source = cls(uri.text, uri.target, speed=speed, timeline=timeline)
        uri.finish()
        return source

    def camera_model(self) -> CameraModel | None:
        """The camera model the run was recorded with (``camera`` in its ``run.json``); None if it had none."""
        try:
            recorded = json.loads((self.run_dir / "run.json").read_text(encoding="utf-8")).get("camera")
            if not isinstance(recorded, dict):
                return None
            return CameraModel.from_dict(recorded, f"recorded in {self.run_dir.name}: {recorded.get('origin', '')}")
        except (OSError, ValueError, AttributeError) as exc:  # CameraModelError is a ValueError
            logger.warning("%r: the camera model in run.json is unreadable (%s): none", self, exc)
            return None

    def _open_device(self) -> None:
        if not (self.run_dir / "run.json").is_file():
            raise SourceError(f"{self.run_dir} is not a recorded run (no run.json); `uav-tui runs` lists them")
        self.content, self._frames = recorded_frames(self.run_dir)
        if not self._frames:
            raise SourceError(f"{self.run_dir}: no video (recorded before record_video existed) and no saved "
                              "frames: there is nothing to replay")
        if self.content != "video" and not self.shown:
            logger.warning("%s has no video (recorded before record_video existed): replaying its %d saved frames "
                           "only", self.run_dir, len(self._frames))
        self._images = self._decode() if self.content == "video" else self._saved()
        for _ in range(self.shown):  # reopened after a decoding error: go on where it stopped
            next(self._images, None)
        first = next(self._images, None)
        if first is None:
            raise SourceError(f"{self.run_dir / VIDEO_FILE}: no frame can be decoded (corrupt file?)")
        self.height, self.width = first.shape[:2]
        self._images = _prepend(first, self._images)
        duration_s = (self._frames[-1][0] - self._frames[0][0]) / 1e9
        self.fps = (len(self._frames) - 1) / duration_s if duration_s > 0 else 0.0

    def _decode(self) -> Generator[np.ndarray, None, None]:
        return read_video(self.run_dir / VIDEO_FILE)

    def _saved(self) -> Generator[np.ndarray, None, None]:
        for _, _, name in self._frames:
            image = cv2.imread(str(self.run_dir / name))
            if image is None:
                raise SourceError(f"{self.run_dir / name}: missing or not an image")
            yield image

    def _grab(self) -> np.ndarray | None:
        assert self._images is not None
        image = next(self._images, None) if self.shown < len(self._frames) else None
        if image is None:
            self._end()
            return None
        t_mono, t_wall = self._frames[self.shown][:2]
        if not self._wait_until(t_mono):
            return None
        self.shown += 1
        self._times = (t_mono, t_wall)
        return image

    def _capture_times(self) -> tuple[int | None, int | None]:
        return self._times or (None, None)

    def _wait_until(self, t_ns: int) -> bool:
        if self.timeline is not None:
            return self.timeline.show(t_ns, self._stop)
        if self.speed is None:
            while not self.buffer.wait_read(timeout=0.1):
                if self._stop.is_set():
                    return False
            return True
        if self._started is None:
            self._started = (t_ns, time.monotonic_ns())
        due_ns = self._started[1] + (t_ns - self._started[0]) / self.speed
        delay_s = (due_ns - time.monotonic_ns()) / 1e9
        return not (delay_s > 0 and self._stop.wait(delay_s))

    def _end(self) -> None:
        """The recording is over: say so, let the replayed telemetry run out, and wait to be closed."""
        self.finished.set()
        if self.timeline is not None:
            self.timeline.finish(self._stop)
        self._stop.wait()

    def _close_device(self) -> None:
        if self._images is not None:
            self._images.close()  # a video's decoder closes its file
            self._images = None

    def _extra_properties(self) -> dict[str, Any]:
        return {"content": self.content, "frames_recorded": len(self._frames), "frames_shown": self.shown,
                "finished": self.finished.is_set(), "speed": "max" if self.speed is None else self.speed}


def _prepend(first: np.ndarray, rest: Iterator[np.ndarray]) -> Generator[np.ndarray, None, None]:
    yield first
    yield from rest
