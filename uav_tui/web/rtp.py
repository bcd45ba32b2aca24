"""Where the ground-station video goes (``video_out = "rtp://HOST:PORT"``) and the session description of it.

Apart from :mod:`uav_tui.web.ground_video` so that checking the configuration imports neither PyAV nor the web side.
"""

from __future__ import annotations

from dataclasses import dataclass
from urllib.parse import urlsplit

RTP_UDP, RTSP = "rtp-udp", "rtsp"
"""The kinds of ground-station stream (a target's ``kind``), as the MAVLink camera component announces them."""
PAYLOAD_TYPE = 96
"""The RTP payload type of the H.264 stream (FFmpeg's first dynamic one; QGC's and GStreamer's default)."""


@dataclass(frozen=True)
class Destination:
    """Where the stream goes: ``rtp://HOST:PORT``."""

    host: str
    port: int

    @classmethod
    def parse(cls, uri: str) -> Destination:
        """``rtp://HOST:PORT`` (``udp://`` is taken as the same); ValueError saying what is expected."""
        parts = urlsplit(uri.strip())
        try:
            port = parts.port
        except ValueError:
            port = None
        if parts.scheme not in ("rtp", "udp") or not parts.hostname or port is None or port == 0:
            raise ValueError(f"video_out {uri!r} must be rtp://HOST:PORT, e.g. rtp://192.168.1.10:5600 (the ground "
                             "station's address; QGroundControl listens on UDP 5600)")
        return cls(parts.hostname, port)

    @property
    def uri(self) -> str:
        return f"rtp://{self.host}:{self.port}"

    def sdp(self) -> str:
        """The session description a receiver without MAVLink needs (VLC, FFmpeg, GStreamer's sdpdemux)."""
        return (f"v=0\r\no=- 0 0 IN IP4 {self.host}\r\ns=uav-tui\r\nc=IN IP4 {self.host}\r\nt=0 0\r\n"
                f"m=video {self.port} RTP/AVP {PAYLOAD_TYPE}\r\na=rtpmap:{PAYLOAD_TYPE} H264/90000\r\n"
                f"a=fmtp:{PAYLOAD_TYPE} packetization-mode=1\r\n")
