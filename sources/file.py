"""``file:PATH`` — a video file replayed in a loop, paced at its own frame rate."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import cv2
import numpy as np

from sources.errors import SourceError
from sources.pacing import Pacer
from sources.uri import SourceUri
from sources.videocapture import VideoCaptureSource

DEFAULT_FPS = 30.0
"""Used when a file does not state its frame rate."""


class FileSource(VideoCaptureSource):
    """Replays an MP4/AVI (anything FFmpeg reads), starting over at the end.

    URI: ``file:PATH[?realtime=1&width=W&height=H]``. Frames come at the file's FPS, like a camera
    (a slow reader skips frames). ``realtime=0`` replays every frame, as fast as the reader takes them:
    the next frame is decoded while the reader works on the current one, and none is skipped.
    """

    kind = "file"
    _backend = cv2.CAP_FFMPEG

    def __init__(self, uri: str, path: str, *, realtime: bool = True, width: int | None = None,
                 height: int | None = None) -> None:
        super().__init__(uri, str(Path(path).expanduser()), width=width, height=height)
        self.realtime = realtime
        self.loops = 0
        self.frame_count = 0
        self._pacer: Pacer | None = None

    @classmethod
    def from_uri(cls, uri: SourceUri, **_context: Any) -> FileSource:
        if not uri.target:
            raise SourceError(f"{uri.text!r}: give the video path, e.g. file:flight.mp4")
        source = cls(uri.text, uri.target, realtime=uri.take_bool("realtime", True),
                     width=uri.take_int("width"), height=uri.take_int("height"))
        uri.finish()
        return source

    def _open_device(self) -> None:
        path = Path(self.device)
        if not path.is_file():
            raise SourceError(f"no such video file: {path} (working directory: {Path.cwd()})")
        super()._open_device()
        assert self._capture is not None
        self.frame_count = int(self._capture.get(cv2.CAP_PROP_FRAME_COUNT))
        self.fps = self.fps if self.fps > 0 else DEFAULT_FPS
        self._pacer = Pacer(self.fps if self.realtime else 0, self._stop)

    def _open_error(self) -> Exception:
        return SourceError(f"{self.device}: not a video FFmpeg can read (unsupported format or corrupt file)")

    def _no_frame_error(self) -> Exception:
        return SourceError(f"{self.device}: opened but no frame could be decoded (corrupt or truncated file?)")

    def _grab(self) -> np.ndarray | None:
        assert self._pacer is not None
        if self.realtime:
            return super()._grab() if self._pacer.wait() else None
        image = super()._grab()  # decoded while the reader still has the previous frame
        while not self.buffer.wait_read(timeout=0.1):
            if self._stop.is_set():
                return None
        return image

    def _read_frame(self) -> np.ndarray | None:
        assert self._capture is not None
        ok, image = self._capture.read(self._target())
        if not ok:  # end of file: start over
            self.loops += 1
            self._capture.set(cv2.CAP_PROP_POS_FRAMES, 0)
            ok, image = self._capture.read(self._target())
        return image if ok else None

    def _extra_properties(self) -> dict[str, Any]:
        return {**super()._extra_properties(), "realtime": self.realtime, "loops": self.loops,
                "frame_count": self.frame_count}
