"""The run's camera stream: ``video.ts`` (H.264 or MJPEG in MPEG-TS) and its index ``video.csv``.

Every captured frame is copied on the capture thread (before the processor may draw on it) and
queued to the disk writer like a JPEG; the writer thread encodes it (:class:`VideoStage`). MPEG-TS
is a stream of self-contained 188-byte packets with no index at the end, so a file cut anywhere
(SIGKILL, power loss) plays up to the cut; encoded bytes are appended on every writer tick, before
the index rows that name them are written, so every indexed frame is on disk.
PyAV rather than OpenCV's ``VideoWriter``: 3.4 ms per 640x480 frame for H.264 in MPEG-TS against 6.8 ms
for OpenCV's MJPEG AVI, whose index at the end is lost when the process is killed.

``video.csv`` has one row per captured frame: its position in the video (``video_frame``, empty
when it was dropped, with the reason in ``dropped``), the frame id it got when it was processed
(empty for frames the processor skipped: ``frames.csv`` joins on it), and its capture times.
"""

from __future__ import annotations

import fractions
import logging
import os
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

from uav_tui.recording.writer import DiskWriter, Pixels, Row

logger = logging.getLogger(__name__)

VIDEO_FILE = "video.ts"
INDEX_TABLE = "video"
INDEX_COLUMNS: tuple[str, ...] = ("video_frame", "frame_id", "seq", "t_mono_ns", "t_wall_ns", "dropped")
"""video.csv: position in ``video.ts`` (0-based, decode order), frame id, capture seq and times, drop reason."""

TIME_BASE = fractions.Fraction(1, 90_000)
"""MPEG-TS clock: presentation times are the capture times, so the video keeps the camera's real timing."""

UNPROCESSED_AFTER_NS = 5_000_000_000
"""A frame not processed while the camera captured for this long after it is indexed without a frame id."""

ENCODERS = (("libx264", "h264", {"preset": "ultrafast", "tune": "zerolatency", "crf": "23"}),
            ("mjpeg", "mjpeg", {"q:v": "4"}))
"""Tried in order: H.264 where FFmpeg has x264 (about 2 ms of one core per 640x480 frame), else MJPEG."""


def choose_encoder() -> tuple[str, str, dict[str, str]]:
    """(FFmpeg encoder, codec name, options) of the first :data:`ENCODERS` entry this FFmpeg has."""
    import av

    available = av.codecs_available
    return next(entry for entry in ENCODERS if entry[0] in available)


def describe_video() -> dict[str, Any]:
    """What ``run.json`` says about the video (``video`` key)."""
    encoder, codec, _ = choose_encoder()
    return {"file": VIDEO_FILE, "index": f"{INDEX_TABLE}.csv", "container": "mpegts", "codec": codec,
            "encoder": encoder}


@dataclass(slots=True)
class VideoFrame(Pixels):
    """A captured frame for the video (its own copy of the pixels)."""

    seq: int = 0
    t_mono_ns: int = 0
    t_wall_ns: int = 0


@dataclass(slots=True)
class VideoDrop:
    """A captured frame that could not be queued (its index row says why)."""

    seq: int
    t_mono_ns: int
    t_wall_ns: int
    reason: str


@dataclass(slots=True)
class FrameLink:
    """The frame captured at ``t_mono_ns`` was processed as frame ``frame_id``."""

    t_mono_ns: int
    frame_id: int


class _Bytes:
    """The file-like object the muxer writes into; the stage appends it to ``video.ts`` on each tick."""

    def __init__(self) -> None:
        self.data = bytearray()

    def write(self, data: bytes) -> int:
        self.data += data
        return len(data)


class VideoStage:
    """Writer-thread stage: encodes :class:`VideoFrame` items and produces the ``video.csv`` rows.

    Args:
        writer: the disk writer this stage runs in (its disk guards and byte count apply to the video).
        encoder: an :data:`ENCODERS` entry (default: :func:`choose_encoder`).
    """

    accepts: tuple[type, ...] = (VideoFrame, VideoDrop, FrameLink)

    def __init__(self, writer: DiskWriter, encoder: tuple[str, str, dict[str, str]] | None = None) -> None:
        self.path = writer.run_dir / VIDEO_FILE
        self.encoder, self.codec, self._options = encoder or choose_encoder()
        self.frames_encoded = 0
        self._writer = writer
        self._sink = _Bytes()
        self._container: Any = None
        self._stream: Any = None
        self._fd: int | None = None
        self._size: tuple[int, int] | None = None
        self._first_ns = 0
        self._last_pts = -1
        self._newest_ns = 0
        self._waiting: deque[list[Any]] = deque()

    def handle(self, item: Any) -> Iterable[Row]:
        if isinstance(item, VideoFrame | VideoDrop):
            self._newest_ns = max(self._newest_ns, item.t_mono_ns)
        if isinstance(item, VideoFrame):
            reason = self._writer.image_refused()
            reason = None if reason == "closed" else reason  # frames queued before the close are written
            position = None if reason else self._encode(item)
            self._waiting.append([position, None, item.seq, item.t_mono_ns, item.t_wall_ns, reason or ""])
        elif isinstance(item, VideoDrop):
            self._waiting.append([None, None, item.seq, item.t_mono_ns, item.t_wall_ns, item.reason])
        else:
            for row in self._waiting:
                if row[3] == item.t_mono_ns:
                    row[1] = item.frame_id
            return self._release(item.t_mono_ns + 1)
        return []

    def due(self, now_ns: int) -> Iterable[Row]:
        """Rows of frames captured :data:`UNPROCESSED_AFTER_NS` before the newest capture (capture stamps, not
        this clock: a replay recording its camera carries the recorded ones)."""
        return self._release(self._newest_ns - UNPROCESSED_AFTER_NS) if self._waiting else []

    def drain(self) -> Iterable[Row]:
        try:
            if self._stream is not None:
                for packet in self._stream.encode():
                    self._container.mux(packet)
                self._container.close()
                self._container = self._stream = None
            return self._release(None)
        finally:
            if self._fd is not None:
                os.close(self._fd)
                self._fd = None

    def _release(self, before_ns: int | None) -> list[Row]:
        """Index rows of frames captured before ``before_ns`` (all: None), after their bytes are on disk."""
        rows = []
        while self._waiting and (before_ns is None or self._waiting[0][3] < before_ns):
            rows.append(Row(INDEX_TABLE, self._waiting.popleft()))
        if rows:
            self._write_out()
        return rows

    def _encode(self, item: VideoFrame) -> int:

        image = item.image
        if self._stream is None:
            self._open(image.shape[1], image.shape[0], item.t_mono_ns)
        if (image.shape[1], image.shape[0]) != self._size:  # the camera was switched: keep one stream size
            image = cv2.resize(image, self._size, interpolation=cv2.INTER_AREA)
        frame = _video_frame(np.ascontiguousarray(image), self._stream.pix_fmt)
        frame.pts = max(self._last_pts + 1, round((item.t_mono_ns - self._first_ns) * TIME_BASE.denominator / 1e9))
        frame.time_base = TIME_BASE
        self._last_pts = frame.pts
        for packet in self._stream.encode(frame):
            self._container.mux(packet)
        self.frames_encoded += 1
        return self.frames_encoded - 1

    def _open(self, width: int, height: int, first_ns: int) -> None:
        import av

        self._size, self._first_ns = (width, height), first_ns
        self._fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        self._container = av.open(self._sink, mode="w", format="mpegts")
        stream = self._container.add_stream(self.encoder, rate=30)
        stream.width, stream.height = width, height
        stream.pix_fmt = "yuvj420p" if self.codec == "mjpeg" else "yuv420p"
        stream.codec_context.time_base = TIME_BASE
        stream.thread_count = 1  # the writer thread's share of the CPU stays one core at most
        stream.options = self._options
        self._stream = stream

    def _write_out(self) -> None:
        data = self._sink.data
        if self._fd is None or not data:
            return
        written = 0
        try:
            while written < len(data):
                written += os.write(self._fd, data[written:])
        except OSError as exc:  # a full disk: the bytes are lost (the stream resumes with the next ones that fit)
            self._writer.lose(exc, "video bytes", len(data) - written, f"{VIDEO_FILE}: {exc}")
        finally:
            self._writer.bytes_written += written
            del data[:]


def _video_frame(image: np.ndarray, pix_fmt: str) -> Any:
    """An encoder frame from a BGR image. For H.264's yuv420p (BT.601, limited range) OpenCV converts:
    4x faster than FFmpeg's default scaler, without its bias (about 2 levels darker), and the ``run:``
    source converts back the same way."""
    import av

    height, width = image.shape[:2]
    if pix_fmt == "yuv420p" and width % 2 == 0 and height % 2 == 0:
        i420: np.ndarray = cv2.cvtColor(image, cv2.COLOR_BGR2YUV_I420)  # uint8, as the input
        return av.VideoFrame.from_ndarray(i420, format="yuv420p")
    return av.VideoFrame.from_ndarray(image, format="bgr24")
