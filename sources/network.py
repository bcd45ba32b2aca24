"""``rtsp://``, ``rtsps://``, ``http(s)://`` — network streams read through OpenCV's FFmpeg backend.

Anything FFmpeg reads works (RTSP cameras, MJPEG over HTTP, HLS). The stream is opened with
low-latency options and bounded open/read timeouts, so a dead stream shows up as a stall within
seconds and the capture base reopens it with back-off.
"""

from __future__ import annotations

import os
import threading
import time
from typing import Any
from urllib.parse import urlsplit

import cv2

from sources.errors import SourceError
from sources.uri import SourceUri, redact
from sources.videocapture import VideoCaptureSource

OPTIONS_ENV = "OPENCV_FFMPEG_CAPTURE_OPTIONS"
"""OpenCV reads FFmpeg's open options from this variable when a capture opens."""

LOW_LATENCY_OPTIONS = {
    "rtsp": "rtsp_transport;tcp|fflags;nobuffer|flags;low_delay|analyzeduration;500000",
    "http": "fflags;nobuffer|flags;low_delay",
}
"""FFmpeg options per protocol family: RTP over the RTSP TCP connection (no lost UDP packets, no
NAT trouble), no demuxer buffering, low-delay decoding, half a second of stream analysis at open
(instead of five). A user's own ``OPENCV_FFMPEG_CAPTURE_OPTIONS`` takes precedence."""

OPEN_TIMEOUT_S = 5.0
READ_TIMEOUT_S = 3.0

_env_lock = threading.Lock()
"""The options variable is process-wide: one open at a time sets and restores it."""


class NetworkSource(VideoCaptureSource):
    """A network stream; ``kind`` is its scheme (``rtsp``, ``http``, ...).

    URI: the stream URL itself (``rtsp://user:pass@192.168.1.20:554/stream1``). The URL's own
    query belongs to the server, so this source takes no options from it. Credentials are masked
    in ``device``, logs and errors.
    """

    _backend = cv2.CAP_FFMPEG

    def __init__(self, url: str, *, open_timeout_s: float = OPEN_TIMEOUT_S,
                 read_timeout_s: float = READ_TIMEOUT_S) -> None:
        super().__init__(redact(url), redact(url))
        self.url = url
        self.kind = urlsplit(url).scheme.lower()
        self.open_timeout_s = open_timeout_s
        self.read_timeout_s = read_timeout_s
        family = "rtsp" if self.kind.startswith("rtsp") else "http"
        self.options = os.environ.get(OPTIONS_ENV) or LOW_LATENCY_OPTIONS[family]
        self._open_s = 0.0
        """How long the last attempt to open took (one refused at once is not a timeout)."""

    @classmethod
    def from_uri(cls, uri: SourceUri, **_context: Any) -> NetworkSource:
        parts = urlsplit(uri.target)
        if not parts.hostname:
            raise SourceError(f"{redact(uri.text)!r}: no host in the stream URL, e.g. rtsp://192.168.1.20:554/stream1")
        return cls(uri.target)

    def _new_capture(self) -> cv2.VideoCapture:
        params = [cv2.CAP_PROP_OPEN_TIMEOUT_MSEC, int(self.open_timeout_s * 1000),
                  cv2.CAP_PROP_READ_TIMEOUT_MSEC, int(self.read_timeout_s * 1000)]
        with _env_lock:
            previous = os.environ.get(OPTIONS_ENV)
            os.environ[OPTIONS_ENV] = self.options
            started = time.monotonic()
            try:
                return cv2.VideoCapture(self.url, self._backend, params)
            finally:
                self._open_s = time.monotonic() - started
                if previous is None:
                    del os.environ[OPTIONS_ENV]
                else:
                    os.environ[OPTIONS_ENV] = previous

    def _open_error(self) -> Exception:
        failed = (f"no stream within {self.open_timeout_s:g} s" if self._open_s >= 0.9 * self.open_timeout_s
                  else f"the stream did not open (failed after {self._open_s:.1f} s)")
        return SourceError(f"{self.device}: {failed}: is the server up, the address, port and path right, the "
                           "credentials accepted?")

    def _no_frame_error(self) -> Exception:
        return SourceError(f"{self.device}: connected but no frame arrived within {self.read_timeout_s:g} s")

    def _extra_properties(self) -> dict[str, Any]:
        return {"url": self.device, "ffmpeg_options": self.options}

