"""The optional side channels: the WebRTC page and MAVLink click-to-track (both off by default).

Imported only when one is switched on, so aiortc stays out of a plain run.
"""

from uav_tui.web.server import WebServer

__all__ = ["WebServer"]
