"""The side channels a run starts when configured: the web page and MAVLink click-to-track."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # aiortc and pymavlink are imported only when the side channels are switched on
    from uav_tui.config import WebConfig
    from uav_tui.events import EventLog
    from uav_tui.web.mavlink_tracking import CameraTracking
    from uav_tui.web.server import WebServer
    from uav_tui.web.view import ServedCore


class SideChannels:
    """The web page and MAVLink click-to-track, each started when ``[web]`` switches it on.

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

    async def start(self, core: ServedCore) -> None:
        """Start the channels switched on, serving ``core`` (aiortc and pymavlink are imported only then)."""
        if self.config.web:
            from uav_tui.web.server import WebServer

            self.web = WebServer(core, self.config)
            await self.web.start()
            self.events.emit("info", "web", f"web page: {self.web.url}")
        if self.config.camera_mavlink:
            from uav_tui.web.mavlink_tracking import CameraTracking

            self.camera_tracking = CameraTracking(core, self.config.camera_mavlink)
            await self.camera_tracking.start()
            self.events.emit("info", "web", f"camera tracking on {self.config.camera_mavlink}")

    async def stop(self) -> None:
        """Stop the channels that were started."""
        for side in (self.web, self.camera_tracking):
            if side is not None:
                await side.stop()
