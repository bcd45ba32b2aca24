"""The processed video for a ground station: H.264 over RTP/UDP to ``video_out`` (QGroundControl listens on 5600).

:class:`GroundVideo` is a frame listener of the core like the web page's track: on the loop it only keeps the
newest processed frame (the processor's overlay in it). A thread of its own, ``ground-video``, takes the newest
at each of its ``fps`` slots, scales and converts it once (:func:`~uav_tui.web.tracks.to_video_frame`), encodes it
(FFmpeg through PyAV: the Pi 4's hardware encoder ``h264_v4l2m2m`` where the Pi has one, else ``libx264`` tuned
for latency) and sends it. Nothing waits for it: a slow encoder or network misses slots (``dropped``, counted),
never a frame of the processor. A send that fails (no route, the network gone) is counted and said once; the
stream goes on with the next frame. Each second has a key frame and the stream parameters in band, so a
receiver that joins late (or QGC started after the drone) shows the video within a second.
"""

from __future__ import annotations

import contextlib
import fractions
import logging
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import av

from uav_tui.web.rtp import Destination
from uav_tui.web.tracks import to_video_frame

if TYPE_CHECKING:
    import numpy as np

    from uav_tui.hosting.host import ProcessedFrame
    from uav_tui.web.view import FrameFeed

logger = logging.getLogger(__name__)

HARDWARE_ENCODER_DEVICE = Path("/dev/video11")
"""The Pi 4's V4L2 H.264 encoder node: with it, ``h264_v4l2m2m``; without (a Pi 5 has none), ``libx264``."""
TIME_BASE = fractions.Fraction(1, 90_000)
"""RTP's video clock."""


def choose_encoder() -> str:
    """``h264_v4l2m2m`` on a Pi 4 (its encoder node exists), else ``libx264``."""
    if HARDWARE_ENCODER_DEVICE.exists() and "h264_v4l2m2m" in av.codecs_available:
        return "h264_v4l2m2m"
    return "libx264"


class GroundVideo:
    """Streams the newest processed frame to a ground station, at most ``fps`` a second.

    Args:
        core: the processed frames.
        destination: where to send.
        width: the stream's width in pixels (never scaled up; height keeps the aspect).
        fps: frames a second.
        kbps: the encoder's target bit rate (a telemetry-grade radio carries about 1000).
        encoder: the FFmpeg encoder (default :func:`choose_encoder`).
    """

    def __init__(self, core: FrameFeed, destination: Destination, *, width: int, fps: float, kbps: int,
                 encoder: str | None = None) -> None:
        self.core = core
        self.destination = destination
        self.width, self.fps, self.kbps = width, fps, kbps
        self.encoder = encoder or choose_encoder()
        self.sent = 0
        """Frames encoded and sent."""
        self.dropped = 0
        """Send slots missed because encoding or sending the frame before took longer than a slot."""
        self.errors = 0
        """Frames whose encoding or sending failed."""
        self.size: tuple[int, int] = (0, 0)
        """The stream's frame size (0, 0 before its first frame)."""
        self._newest: ProcessedFrame | None = None
        self._fresh = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._said: set[str] = set()

    def start(self) -> None:
        """Listen to the core's frames and start the sending thread."""
        self.core.add_frame_listener(self.offer)
        self._thread = threading.Thread(target=self._run, name="ground-video", daemon=True)
        self._thread.start()
        logger.info("GroundVideo(%s): %s, %d px, %g fps, %d kbit/s", self.destination.uri, self.encoder, self.width,
                    self.fps, self.kbps)

    def offer(self, result: ProcessedFrame) -> None:
        """Frame listener (on the loop): keep the newest processed frame."""
        self._newest = result
        self._fresh.set()

    def stop(self) -> None:
        """Stop listening (on the loop) and tell the thread to end after the frame it is on. Idempotent."""
        with contextlib.suppress(ValueError, KeyError):
            self.core.remove_frame_listener(self.offer)
        self._stop.set()
        self._fresh.set()

    def join(self, timeout_s: float = 2.0) -> None:
        """Wait for the thread to end (off the loop: a frame being encoded finishes first)."""
        if self._thread is not None:
            self._thread.join(timeout=timeout_s)
            self._thread = None

    @property
    def receiver_uri(self) -> str:
        """The stream as a ground station that receives it names it (QGC: ``udp://0.0.0.0:PORT``, RTP H.264)."""
        return f"udp://0.0.0.0:{self.destination.port}"

    def status(self) -> dict[str, Any]:
        return {"uri": self.destination.uri, "encoder": self.encoder, "sent": self.sent, "dropped": self.dropped,
                "errors": self.errors}

    def _run(self) -> None:
        interval = 1.0 / self.fps
        output: _Output | None = None
        taken: ProcessedFrame | None = None
        next_slot = 0.0
        try:
            while True:
                self._fresh.wait()
                self._fresh.clear()
                if self._stop.is_set() or self._stop.wait(max(0.0, next_slot - time.monotonic())):
                    break
                result = self._newest  # the newest now: it may have changed while this waited for the slot
                if result is None or result is taken:
                    continue
                taken = result
                began = time.monotonic()
                output = self._send(output, result.frame.image)
                self.dropped += int((time.monotonic() - began) / interval)  # slots this frame's send took
                next_slot = began + interval
        finally:
            if output is not None:
                output.close()

    def _send(self, output: _Output | None, image: np.ndarray) -> _Output | None:
        try:
            frame = to_video_frame(image, self.width)
            if output is None:
                output = _Output(self.destination, self.encoder, frame.width, frame.height, self.fps, self.kbps)
                self.size = (frame.width, frame.height)
            output.send(frame)
        except (av.FFmpegError, OSError, ValueError) as exc:
            self.errors += 1
            self._say_once(f"{type(exc).__name__}: {exc}")
            if output is not None:
                output.close()
            return None
        self.sent += 1
        return output

    def _say_once(self, text: str) -> None:
        kind = text.split(":")[0]
        if kind not in self._said and len(self._said) < 16:
            self._said.add(kind)
            logger.warning("GroundVideo(%s): a frame was not sent (%s); the stream goes on, counted in errors",
                           self.destination.uri, text)


class _Output:
    """One RTP session: FFmpeg's H.264 encoder and RTP muxer on a UDP socket."""

    def __init__(self, destination: Destination, encoder: str, width: int, height: int, fps: float,
                 kbps: int) -> None:
        self._container: Any = av.open(f"{destination.uri}?pkt_size=1200", "w", format="rtp")
        try:
            stream: Any = self._container.add_stream(encoder, rate=round(fps))
            stream.width, stream.height, stream.pix_fmt = width, height, "yuv420p"
            stream.bit_rate = kbps * 1000
            stream.codec_context.time_base = TIME_BASE
            stream.codec_context.gop_size = max(1, round(fps))  # a key frame each second
            if encoder == "libx264":
                stream.options = {"preset": "ultrafast", "tune": "zerolatency",
                                  "x264-params": f"keyint={max(1, round(fps))}:repeat-headers=1"}
            self._stream = stream
            self._started = time.monotonic()
        except BaseException:
            self._container.close()
            raise

    def send(self, frame: Any) -> None:
        frame.pts = round((time.monotonic() - self._started) / TIME_BASE)
        frame.time_base = TIME_BASE
        for packet in self._stream.encode(frame):
            self._container.mux(packet)

    def close(self) -> None:
        with contextlib.suppress(av.FFmpegError, OSError, ValueError):
            self._container.close()
