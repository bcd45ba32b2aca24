"""The optional side channels: the WebRTC page and MAVLink click-to-track (both off by default).

:class:`~uav_tui.web.side_channels.SideChannels` starts the ones switched on; aiortc (``WebServer``, imported on
first use of the name) and pymavlink stay out of a plain run.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from uav_tui.web.server import WebServer

__all__ = ["WebServer"]


def __getattr__(name: str) -> Any:
    if name == "WebServer":
        from uav_tui.web.server import WebServer

        return WebServer
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
