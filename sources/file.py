"""``file:PATH`` — a video file replayed in a loop, paced at its own frame rate."""

from __future__ import annotations

import contextlib
import functools
import logging
import os
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from sources.decoder_threads import SINGLE, DecoderThreads
from sources.errors import SourceError
from sources.pacing import Pacer
from sources.uri import SourceUri
from sources.videocapture import VideoCaptureSource

logger = logging.getLogger(__name__)

DEFAULT_FPS = 30.0
"""Used when a file does not state its frame rate."""
NICENESS = 2
"""How much lower than the platform's the priority of a replay's decoding is (its capture thread, and FFmpeg's
frame threads, whichever thread opened the file), so decoding ahead takes the CPU the processor and the event
loop leave. Real 1280x720 video on 2 cores, every core busy: a processor waiting for a frame was woken 1.1 ms late
at p95, 0.5-0.9 ms with 2 levels. With 5 levels it was 0.3 ms, but YOLO, whose own threads fill every core, lost
11 % of its FPS."""


class FileSource(VideoCaptureSource):
    """Replays an MP4/AVI (anything FFmpeg reads), starting over at the end.

    URI: ``file:PATH[?realtime=1&width=W&height=H&threads=N]``. Frames come at the file's FPS, like a camera
    (a slow reader skips frames). ``realtime=0`` replays every frame, as fast as the reader takes them:
    the next frame is decoded while the reader works on the current one, and none is skipped.

    FFmpeg decodes on one thread unless its own frame threads replay faster (:mod:`sources.decoder_threads`
    measures both): the file is reopened at the next frame, and the switch is kept only if the reopened
    file decodes that frame exactly as the current one does. ``threads=N`` fixes the count (0: FFmpeg's choice).
    """

    kind = "file"
    _backend = cv2.CAP_FFMPEG

    def __init__(self, uri: str, path: str, *, realtime: bool = True, width: int | None = None,
                 height: int | None = None, threads: int | None = None) -> None:
        super().__init__(uri, str(Path(path).expanduser()), width=width, height=height)
        self.realtime = realtime
        self.loops = 0
        self.frame_count = 0
        self._pacer: Pacer | None = None
        self._adaptive = threads is None
        self._decoder = DecoderThreads(threads=SINGLE if threads is None else threads)
        self._decoding_niceness = min(19, os.getpriority(os.PRIO_PROCESS, 0) + NICENESS)
        """The priority decoding runs at (on Linux, ``os.getpriority`` of 0 is the calling thread's)."""
        self._position = 0
        """Index of the next frame the capture decodes."""
        self._reopened: tuple[cv2.VideoCapture, int] | None = None
        """The file reopened on another thread count at ``_position``; adopted once it decodes the same frame."""

    @classmethod
    def from_uri(cls, uri: SourceUri, **_context: Any) -> FileSource:
        if not uri.target:
            raise SourceError(f"{uri.text!r}: give the video path, e.g. file:flight.mp4")
        source = cls(uri.text, uri.target, realtime=uri.take_bool("realtime", True),
                     width=uri.take_int("width"), height=uri.take_int("height"), threads=uri.take_int("threads"))
        uri.finish()
        return source

    def _new_capture(self) -> cv2.VideoCapture:
        return self._capture_on(self._decoder.threads)

    def _capture_on(self, threads: int) -> cv2.VideoCapture:
        """Opened on one decoder thread (the capture thread), or on a thread at the decoding priority, which the
        frame threads FFmpeg starts as it opens inherit."""
        open_capture = functools.partial(cv2.VideoCapture, self.device, self._backend,
                                         [cv2.CAP_PROP_N_THREADS, threads])
        if threads == SINGLE:
            return open_capture()
        with ThreadPoolExecutor(1, initializer=self._lower_priority) as decoding_priority:
            return decoding_priority.submit(open_capture).result()

    def _lower_priority(self) -> None:
        """Give the calling thread the decoding priority (Linux only: elsewhere a priority is the whole process's)."""
        if sys.platform == "linux":
            with contextlib.suppress(OSError):
                os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), self._decoding_niceness)

    def _open_device(self) -> None:
        path = Path(self.device)
        if not path.is_file():
            raise SourceError(f"no such video file: {path} (working directory: {Path.cwd()})")
        super()._open_device()
        self._position = 1  # opening decoded the first frame
        assert self._capture is not None
        self.frame_count = int(self._capture.get(cv2.CAP_PROP_FRAME_COUNT))
        self.fps = self.fps if self.fps > 0 else DEFAULT_FPS
        self._pacer = Pacer(self.fps if self.realtime else 0, self._stop)

    def _open_error(self) -> Exception:
        return SourceError(f"{self.device}: not a video FFmpeg can read (unsupported format or corrupt file)")

    def _no_frame_error(self) -> Exception:
        return SourceError(f"{self.device}: opened but no frame could be decoded (corrupt or truncated file?)")

    def _capture_loop(self) -> None:
        self._lower_priority()
        super()._capture_loop()

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
        target = self._target()
        ok, image = self._capture.read(target)
        if not ok:  # end of file: start over
            self.loops += 1
            self._position = 0
            self._capture.set(cv2.CAP_PROP_POS_FRAMES, 0)
            if self._reopened is not None:  # due at the frame after this end: now the first
                self._reopened[0].set(cv2.CAP_PROP_POS_FRAMES, 0)
            ok, image = self._capture.read(target)
        if not ok:
            return None
        if self._reopened is not None:
            self._adopt_reopened(image)
        self._position += 1
        if self._adaptive:
            threads = self._decoder.frame(time.monotonic())
            if threads is not None:
                self._reopen(threads)
        return image

    def _reopen(self, threads: int) -> None:
        """Open the file again on ``threads`` decoder threads at the next frame; adopted by the next read."""
        reopened = self._open_at(threads, self._position)
        if reopened is None:
            self._stop_adapting("it could not be reopened at the current frame")
        else:
            self._reopened = reopened, threads

    def _open_at(self, threads: int, position: int) -> cv2.VideoCapture | None:
        capture = self._capture_on(threads)
        if capture.isOpened() and capture.set(cv2.CAP_PROP_POS_FRAMES, position):
            return capture
        capture.release()
        return None

    def _adopt_reopened(self, image: np.ndarray) -> None:
        """Switch to the reopened file if it decodes the frame just read exactly as the current one did."""
        assert self._reopened is not None and self._capture is not None
        (reopened, threads), self._reopened = self._reopened, None
        ok, same_frame = reopened.read()
        if not ok or not np.array_equal(same_frame, image):
            reopened.release()
            self._stop_adapting("after a seek it decodes another frame than the one due")
            return
        self._capture.release()
        self._capture = reopened
        self._decoder.switched(threads, time.monotonic())
        logger.info("%r: decoding on %s from frame %d", self, _threads_text(reopened), self._position)

    def _stop_adapting(self, why: str) -> None:
        self._adaptive = False
        assert self._capture is not None
        logger.warning("%r: keeps decoding on %s: %s", self, _threads_text(self._capture), why)

    def _close_device(self) -> None:
        if self._reopened is not None:
            self._reopened[0].release()
            self._reopened = None
        super()._close_device()

    def _extra_properties(self) -> dict[str, Any]:
        return {**super()._extra_properties(), "realtime": self.realtime, "loops": self.loops,
                "frame_count": self.frame_count, "decoder_threads": self._decoder.threads or "ffmpeg",
                "decoder_threads_adaptive": self._adaptive}


def _threads_text(capture: cv2.VideoCapture) -> str:
    threads = int(capture.get(cv2.CAP_PROP_N_THREADS))
    return "one thread" if threads == 1 else f"FFmpeg's {threads} threads"
