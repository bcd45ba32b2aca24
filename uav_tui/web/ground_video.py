"""The processed video for a ground station: H.264 over RTP/UDP to ``video_out`` (QGroundControl listens on 5600) and
as an RTSP stream (``video_rtsp_port``, :mod:`uav_tui.web.rtsp`).

:class:`GroundVideo` is a frame listener of the core like the web page's track: on the loop it only keeps the
newest processed frame (the processor's overlay in it). A thread of its own, ``ground-video``, takes the newest
at each of its ``fps`` slots, scales and converts it once (:func:`~uav_tui.web.tracks.to_video_frame`), encodes it
(FFmpeg through PyAV: the Pi 4's hardware encoder ``h264_v4l2m2m`` where the Pi has one, else ``libx264`` tuned
for latency) and hands it to its :class:`Target` (RTP, or the RTSP server). Nothing waits for it: a slow encoder or
network misses slots (``dropped``, counted), never a frame of the processor; a frame the target takes no one to
(an RTSP stream without a client, or one whose queue is full) is counted in ``unsent``. A send that fails (no
route, the network gone) is counted and said once; the stream goes on with the next frame. Each second has a key
frame and the stream parameters in band, so a receiver that joins late (or QGC started after the drone) shows the
video within a second.
"""

from __future__ import annotations

import contextlib
import fractions
import logging
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import av

from uav_tui.web.rtp import RTP_UDP
from uav_tui.web.tracks import to_video_frame

if TYPE_CHECKING:
    import numpy as np

    from uav_tui.relays.contract import HandledFrame
    from uav_tui.web.rtp import Destination
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


def configure_encoder(context: Any, encoder: str, width: int, height: int, fps: float, kbps: int, *,
                      one_slice: bool = False) -> None:
    """Set up an H.264 encoder's codec context for a live stream: a key frame and the parameters each second.

    ``one_slice``: ``libx264`` on one thread, each frame one slice (else one slice a thread, for latency).
    """
    context.width, context.height, context.pix_fmt = width, height, "yuv420p"
    context.framerate = fractions.Fraction(round(fps))
    context.bit_rate = kbps * 1000
    context.time_base = TIME_BASE
    context.gop_size = max(1, round(fps))
    if encoder == "libx264":
        context.options = {"preset": "ultrafast", "tune": "zerolatency",
                           "x264-params": f"keyint={max(1, round(fps))}:repeat-headers=1"
                                          + (":threads=1" if one_slice else "")}


def stamp(frame: Any, started: float) -> None:
    """Give ``frame`` its presentation time on the 90 kHz clock, counted from ``started`` (monotonic s)."""
    frame.pts = round((time.monotonic() - started) / TIME_BASE)
    frame.time_base = TIME_BASE


class Output(Protocol):
    """One encoding session of a target, opened at the stream's frame size."""

    def send(self, frame: Any) -> bool:
        """Encode ``frame`` and send it; False when it went to no one (counted in ``unsent``)."""
        ...

    def close(self) -> None: ...


class Target(Protocol):
    """Where a :class:`GroundVideo` sends: RTP to a ground station, or an RTSP server its clients play from."""

    @property
    def kind(self) -> str:
        """:data:`~uav_tui.web.rtp.RTP_UDP` or :data:`~uav_tui.web.rtp.RTSP`."""
        ...

    @property
    def uri(self) -> str:
        """Where it goes, as logs and the status say it."""
        ...

    @property
    def watched(self) -> bool:
        """Whether a frame now reaches anyone (RTP cannot tell: always True); when not, none is even converted."""
        ...

    def receiver_uri(self, host: str) -> str:
        """The stream as a ground station that reaches this machine at ``host`` opens it."""
        ...

    def open(self, encoder: str, width: int, height: int, fps: float, kbps: int) -> Output: ...

    def close(self) -> None:
        """Release what the target holds (after its last frame)."""
        ...


class GroundVideo:
    """Streams the newest processed frame to a ground station, at most ``fps`` a second.

    Args:
        core: the processed frames.
        target: where to send (:class:`RtpTarget`, :class:`~uav_tui.web.rtsp.RtspServer`).
        width: the stream's width in pixels (never scaled up; height keeps the aspect).
        fps: frames a second.
        kbps: the encoder's target bit rate (a telemetry-grade radio carries about 1000).
        encoder: the FFmpeg encoder (default :func:`choose_encoder`).
    """

    def __init__(self, core: FrameFeed, target: Target, *, width: int, fps: float, kbps: int,
                 encoder: str | None = None) -> None:
        self.core = core
        self.target = target
        self.width, self.fps, self.kbps = width, fps, kbps
        self.encoder = encoder or choose_encoder()
        self.sent = 0
        """Frames encoded and sent."""
        self.dropped = 0
        """Send slots missed because encoding or sending the frame before took longer than a slot."""
        self.unsent = 0
        """Frames that went to no one: an RTSP stream without a client, or a client too slow to take them."""
        self.errors = 0
        """Frames whose encoding or sending failed."""
        self.size: tuple[int, int] = (0, 0)
        """The stream's frame size (0, 0 before its first frame)."""
        self._newest: HandledFrame | None = None
        self._fresh = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._said: set[str] = set()

    def start(self) -> None:
        """Listen to the core's frames and start the sending thread."""
        self.core.add_frame_listener(self.offer)
        self._thread = threading.Thread(target=self._run, name="ground-video", daemon=True)
        self._thread.start()
        logger.info("GroundVideo(%s): %s, %d px, %g fps, %d kbit/s", self.target.uri, self.encoder, self.width,
                    self.fps, self.kbps)

    def offer(self, result: HandledFrame) -> None:
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
        """Wait for the thread to end (off the loop: a frame being encoded finishes first), then close the target."""
        if self._thread is not None:
            self._thread.join(timeout=timeout_s)
            self._thread = None
            self.target.close()

    def status(self) -> dict[str, Any]:
        return {"uri": self.target.uri, "encoder": self.encoder, "sent": self.sent, "dropped": self.dropped,
                "unsent": self.unsent, "errors": self.errors}

    def _run(self) -> None:
        interval = 1.0 / self.fps
        output: Output | None = None
        taken: HandledFrame | None = None
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
                if not self.target.watched:
                    self.unsent += 1
                    continue
                began = time.monotonic()
                output = self._send(output, result.frame.image)
                self.dropped += int((time.monotonic() - began) / interval)  # slots this frame's send took
                next_slot = began + interval
        finally:
            if output is not None:
                output.close()

    def _send(self, output: Output | None, image: np.ndarray) -> Output | None:
        try:
            frame = to_video_frame(image, self.width)
            if output is None:
                output = self.target.open(self.encoder, frame.width, frame.height, self.fps, self.kbps)
                self.size = (frame.width, frame.height)
            delivered = output.send(frame)
        except (av.FFmpegError, OSError, ValueError) as exc:
            self.errors += 1
            self._say_once(f"{type(exc).__name__}: {exc}")
            if output is not None:
                output.close()
            return None
        if delivered:
            self.sent += 1
        else:
            self.unsent += 1
        return output

    def _say_once(self, text: str) -> None:
        kind = text.split(":")[0]
        if kind not in self._said and len(self._said) < 16:
            self._said.add(kind)
            logger.warning("GroundVideo(%s): a frame was not sent (%s); the stream goes on, counted in errors",
                           self.target.uri, text)


class RtpTarget:
    """H.264 over RTP to one ground station (``video_out``)."""

    kind = RTP_UDP
    watched = True

    def __init__(self, destination: Destination) -> None:
        self.destination = destination
        self.uri = destination.uri

    def receiver_uri(self, host: str) -> str:
        """As QGC names a stream it listens for: ``udp://0.0.0.0:PORT`` (RTP H.264), whatever ``host``."""
        return f"udp://0.0.0.0:{self.destination.port}"

    def open(self, encoder: str, width: int, height: int, fps: float, kbps: int) -> Output:
        return _RtpOutput(self.destination, encoder, width, height, fps, kbps)

    def close(self) -> None:
        """Nothing held between sessions."""


class _RtpOutput:
    """One RTP session: FFmpeg's H.264 encoder and RTP muxer on a UDP socket."""

    def __init__(self, destination: Destination, encoder: str, width: int, height: int, fps: float,
                 kbps: int) -> None:
        self._container: Any = av.open(f"{destination.uri}?pkt_size=1200", "w", format="rtp")
        try:
            self._stream: Any = self._container.add_stream(encoder, rate=round(fps))
            configure_encoder(self._stream.codec_context, encoder, width, height, fps, kbps)
            self._started = time.monotonic()
        except BaseException:
            self._container.close()
            raise

    def send(self, frame: Any) -> bool:
        stamp(frame, self._started)
        for packet in self._stream.encode(frame):
            self._container.mux(packet)
        return True

    def close(self) -> None:
        with contextlib.suppress(av.FFmpegError, OSError, ValueError):
            self._container.close()
