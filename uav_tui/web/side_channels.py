"""The side channels a run starts when configured: the web page, MAVLink click-to-track and the ground-station
video."""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # aiortc and pymavlink are imported only when the side channels are switched on
    from uav_tui.config import WebConfig
    from uav_tui.events import EventLog
    from uav_tui.web.ground_video import GroundVideo, Target
    from uav_tui.web.mavlink_tracking import CameraTracking
    from uav_tui.web.server import WebServer
    from uav_tui.web.view import ServedCore


class SideChannels:
    """The web page, MAVLink click-to-track and the ground-station video, each started when ``[web]`` switches it
    on.

    Args:
        config: the ``[web]`` settings.
        events: where each channel's address is said.
    """

    def __init__(self, config: WebConfig, events: EventLog) -> None:
        self.config = config
        self.events = events
        self.web: WebServer | None = None
        """The web page's WebServer (``web.url`` has the token) when ``web`` is on, else None."""
        self.camera_tracking: CameraTracking | None = None
        """The MAVLink camera component when ``camera_mavlink`` is set, else None."""
        self.video: GroundVideo | None = None
        """The ground-station video over RTP when ``video_out`` is set, else None (the camera component announces
        it)."""
        self.rtsp: GroundVideo | None = None
        """The ground-station video as an RTSP stream when ``video_rtsp_port`` is set, else None (announced too)."""

    async def start(self, core: ServedCore) -> None:
        """Start the channels switched on, serving ``core`` (aiortc, PyAV and pymavlink are imported only then)."""
        if self.config.video_out:
            from uav_tui.web.ground_video import RtpTarget
            from uav_tui.web.rtp import Destination

            destination = Destination.parse(self.config.video_out)
            self.video = self._video(core, RtpTarget(destination))
            self.events.emit("info", "web", f"ground-station video: H.264 over RTP to {destination.uri} "
                             f"({self.video.encoder}); in QGroundControl: Video Source UDP h.264, port "
                             f"{destination.port}")
        if self.config.video_rtsp_port:
            from uav_tui.web.rtsp import RtspServer

            server = RtspServer(self.config.video_rtsp_port, self.config.video_rtsp_path)
            self.rtsp = self._video(core, server)
            self.events.emit("info", "web", f"ground-station video: RTSP on port {server.port}, "
                             f"rtsp://<this machine>:{server.port}{server.path} ({self.rtsp.encoder})")
        if self.config.web:
            from uav_tui.web.server import WebServer

            self.web = WebServer(core, self.config)
            await self.web.start()
            self.events.emit("info", "web", f"web page on {self.web.url.partition('?')[0]} (its token is on the "
                             "terminal; never recorded)")
        if self.config.camera_mavlink:
            from uav_tui.web.mavlink_tracking import CameraTracking

            videos = [video for video in (self.video, self.rtsp) if video is not None]
            self.camera_tracking = CameraTracking(core, self.config.camera_mavlink, videos=videos)
            await self.camera_tracking.start()
            self.events.emit("info", "web", f"camera tracking on {self.config.camera_mavlink}")

    def _video(self, core: ServedCore, target: Target) -> GroundVideo:
        from uav_tui.web.ground_video import GroundVideo

        video = GroundVideo(core, target, width=self.config.video_out_width, fps=self.config.video_out_fps,
                            kbps=self.config.video_out_kbps)
        video.start()
        return video

    async def stop(self) -> None:
        """Stop the channels that were started."""
        for side in (self.web, self.camera_tracking):
            if side is not None:
                await side.stop()
        videos = [video for video in (self.video, self.rtsp) if video is not None]
        self.video = self.rtsp = None
        for video in videos:
            video.stop()
        for video in videos:
            await asyncio.get_running_loop().run_in_executor(None, video.join)
