"""The MAVLink camera component's video streams: VIDEO_STREAM_INFORMATION and VIDEO_STREAM_STATUS of the
ground-station videos, so QGroundControl lists them without an address typed in.

The streams have ids 1, 2, ... in the order given (RTP, then RTSP, when both are on); a request for stream 0 is
answered with each. An RTSP stream's URI names this machine by its address on the route to the ground station
that asked (:func:`address_toward`): a server listening on every address has no one name.
"""

from __future__ import annotations

import contextlib
import math
import socket
from collections.abc import Callable, Sequence
from functools import partial
from typing import TYPE_CHECKING, Any

from pymavlink.dialects.v20 import common as mavlink

from uav_tui.output.text import describe
from uav_tui.web.rtp import RTSP

if TYPE_CHECKING:
    from uav_tui.web.ground_video import GroundVideo
    from uav_tui.web.view import ServedCore

COMMANDS = (mavlink.MAV_CMD_REQUEST_VIDEO_STREAM_INFORMATION, mavlink.MAV_CMD_REQUEST_VIDEO_STREAM_STATUS)
MESSAGES = (mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION, mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_STATUS)
"""The (older) commands and the messages (MAV_CMD_REQUEST_MESSAGE) a ground station asks for video streams with."""


def address_toward(bound: str, peer: tuple[str, int] | None) -> str:
    """This machine's address as ``peer`` reaches it: ``bound`` unless that is every address (0.0.0.0), else the
    source address of the route to ``peer`` (a UDP socket's connect picks it and sends nothing)."""
    if bound not in ("0.0.0.0", "") or peer is None:
        return bound
    with contextlib.suppress(OSError), socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.connect(peer)
        return str(probe.getsockname()[0])
    return bound


class VideoStreams:
    """Answers a ground station's requests for the videos' stream information and status.

    Args:
        mav: the component's MAVLink sender.
        core: the running core (its camera model gives the field of view).
        videos: the streams, ids 1, 2, ...
        address: this machine's address as the asking ground station reaches it.
    """

    def __init__(self, mav: Any, core: ServedCore, videos: Sequence[GroundVideo], address: Callable[[], str]) -> None:
        self.mav, self.core, self.address = mav, core, address
        self.videos = tuple(videos)

    def answer(self, message: Any, requested: int | None,
               origin: str) -> tuple[int, Callable[[], None] | None] | None:
        """(MAV_RESULT, what to send after the ACK) for a video-stream request, None for any other command (or with
        no video: the component has no video streams)."""
        if not self.videos or message.command not in COMMANDS and requested not in MESSAGES:
            return None
        status = message.command == mavlink.MAV_CMD_REQUEST_VIDEO_STREAM_STATUS or \
            requested == mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_STATUS
        asked = message.param2 if requested is not None else message.param1  # the stream id, 0: each
        if asked not in range(len(self.videos) + 1):
            self.core.events.emit("warning", "command", f"video stream request rejected: stream {describe(asked)} "
                                  f"(there are {len(self.videos)}; 0 = each)", origin)
            return mavlink.MAV_RESULT_DENIED, None
        ids = range(1, len(self.videos) + 1) if asked == 0 else range(int(asked), int(asked) + 1)
        return mavlink.MAV_RESULT_ACCEPTED, partial(self._send, self._status if status else self._information, ids)

    @staticmethod
    def _send(send: Callable[[int], None], ids: range) -> None:
        for stream_id in ids:
            send(stream_id)

    def _fields(self, video: GroundVideo) -> tuple[float, int, int, int, int, int]:
        """(framerate, width, height, bit rate, rotation, horizontal field of view) of a stream."""
        width, height = video.size
        camera = self.core.camera
        hfov = round(math.degrees(2 * math.atan(camera.width / (2 * camera.fx)))) if camera is not None else 0
        return video.fps, width, height, video.kbps * 1000, 0, hfov

    def _information(self, stream_id: int) -> None:
        video = self.videos[stream_id - 1]
        kind = mavlink.VIDEO_STREAM_TYPE_RTSP if video.target.kind == RTSP else mavlink.VIDEO_STREAM_TYPE_RTPUDP
        self.mav.video_stream_information_send(
            stream_id, len(self.videos), kind, mavlink.VIDEO_STREAM_STATUS_FLAGS_RUNNING, *self._fields(video),
            f"uav-tui processed {video.target.kind}".encode(), video.target.receiver_uri(self.address()).encode(),
            mavlink.VIDEO_STREAM_ENCODING_H264)

    def _status(self, stream_id: int) -> None:
        self.mav.video_stream_status_send(stream_id, mavlink.VIDEO_STREAM_STATUS_FLAGS_RUNNING,
                                          *self._fields(self.videos[stream_id - 1]))
