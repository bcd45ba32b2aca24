"""The processed video as one WebRTC track, shared by every viewer.

:class:`VideoHub` owns one :class:`ProcessedVideoTrack` while at least one viewer watches and hands
each viewer a relay proxy of it (aiortc's ``MediaRelay``, unbuffered: the newest frame wins), so a
frame is scaled and converted once however many browsers watch; each peer connection still encodes
its own stream (aiortc encodes on its executor, off the loop). With no viewer the hub is not even a
frame listener of the core: streaming costs nothing.
"""

from __future__ import annotations

import asyncio
import fractions
import logging
import time
from concurrent.futures import ThreadPoolExecutor

import cv2
import numpy as np
from aiortc import MediaStreamTrack, VideoStreamTrack
from aiortc.contrib.media import MediaRelay
from aiortc.mediastreams import VIDEO_CLOCK_RATE, VIDEO_TIME_BASE, MediaStreamError
from av import VideoFrame

from uav_tui.relays.contract import HandledFrame
from uav_tui.web.view import FrameFeed

logger = logging.getLogger(__name__)


def to_video_frame(image: np.ndarray, width: int) -> VideoFrame:
    """Scale a BGR image to ``width`` (never up; even sizes) and convert it once, straight to I420."""
    height_in, width_in = image.shape[:2]
    out_w = min(width, width_in) & ~1
    out_h = max(2, round(height_in * out_w / width_in)) & ~1
    if (out_w, out_h) != (width_in, height_in):
        image = cv2.resize(image, (out_w, out_h), interpolation=cv2.INTER_AREA)
    i420: np.ndarray = cv2.cvtColor(image, cv2.COLOR_BGR2YUV_I420)  # uint8, as the input
    return VideoFrame.from_ndarray(i420, format="yuv420p")


class ProcessedVideoTrack(VideoStreamTrack):
    """Sends the newest processed frame (with the processor's overlay), at most ``fps`` per second.

    ``offer`` is the core's frame listener; ``recv`` waits for a frame it has not sent yet, paces
    itself with ``next_timestamp`` and converts the frame on its own thread.

    Args:
        width: width of the streamed video in pixels (frames are never scaled up).
        fps: the most frames per second it sends.
    """

    def __init__(self, width: int, fps: float) -> None:
        super().__init__()
        self.width = width
        self.interval_s = 1.0 / fps
        self.sent = 0
        """Frames converted and handed to the relay."""
        self._newest: HandledFrame | None = None
        self._sent_last: HandledFrame | None = None
        self._fresh = asyncio.Event()
        self._started: float | None = None
        self._last_send = 0.0
        self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="web-video")

    def offer(self, result: HandledFrame) -> None:
        """Frame listener (on the loop): remember the newest processed frame."""
        self._newest = result
        self._fresh.set()

    async def next_timestamp(self) -> tuple[int, fractions.Fraction]:
        """Sleep until the next send slot; the pts follows the real clock, so slow sources keep real time."""
        if self.readyState != "live":
            raise MediaStreamError
        now = time.monotonic()
        if self._started is None:
            self._started = now
        elif (wait := self._last_send + self.interval_s - now) > 0:
            await asyncio.sleep(wait)
            now = time.monotonic()
        self._last_send = now
        return int((now - self._started) * VIDEO_CLOCK_RATE), VIDEO_TIME_BASE

    async def recv(self) -> VideoFrame:
        while self._newest is None or self._newest is self._sent_last:
            if self.readyState != "live":
                raise MediaStreamError
            self._fresh.clear()
            await self._fresh.wait()
        pts, time_base = await self.next_timestamp()
        result = self._newest  # the newest again: it may have changed while we slept
        assert result is not None
        self._sent_last = result
        loop = asyncio.get_running_loop()
        frame = await loop.run_in_executor(self._executor, to_video_frame, result.frame.image, self.width)
        frame.pts, frame.time_base = pts, time_base
        self.sent += 1
        return frame

    def stop(self) -> None:
        super().stop()
        self._fresh.set()  # wake a waiting recv so it raises MediaStreamError
        self._executor.shutdown(wait=False, cancel_futures=True)


class VideoHub:
    """Gives every viewer a track of the processed video; one source track for all of them.

    Args:
        core: the running core's processed frames.
        width: streamed width in pixels.
        fps: streamed frame rate.
    """

    def __init__(self, core: FrameFeed, width: int, fps: float) -> None:
        self._core = core
        self.width, self.fps = width, fps
        self._relay = MediaRelay()
        self.source: ProcessedVideoTrack | None = None
        """The shared source track; None while nobody watches."""
        self._viewers: set[MediaStreamTrack] = set()

    @property
    def viewers(self) -> int:
        return len(self._viewers)

    def subscribe(self) -> MediaStreamTrack:
        """A new viewer's track; starts the shared source when it is the first."""
        if self.source is None:
            self.source = ProcessedVideoTrack(self.width, self.fps)
            self._core.add_frame_listener(self.source.offer)
            logger.info("VideoHub: first viewer, streaming at %d px, %g fps", self.width, self.fps)
        proxy = self._relay.subscribe(self.source, buffered=False)
        self._viewers.add(proxy)
        return proxy

    def unsubscribe(self, track: MediaStreamTrack) -> None:
        """A viewer left; the last one stops the source and the frame listener."""
        if track not in self._viewers:
            return
        self._viewers.discard(track)
        track.stop()
        if not self._viewers and self.source is not None:
            self._core.remove_frame_listener(self.source.offer)
            self.source.stop()
            self.source = None
            logger.info("VideoHub: no viewer left, streaming stopped")

    def close(self) -> None:
        for track in tuple(self._viewers):
            self.unsubscribe(track)
