"""The processed video for a ground station: H.264 over RTP, announced by the MAVLink camera component.

FFmpeg's own command-line tool (Debian's ``ffmpeg``, installed by ``.ci/run``) is the receiver: it is given the
stream by the URI the camera component announces, decodes it and hands the frames to the test.
"""

from __future__ import annotations

import asyncio
import re
import shutil
import socket
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from pymavlink.dialects.v20 import common as mavlink

from tests.web.conftest import free_port, make_core
from tests.web.test_camera_tracking import GroundStation
from uav_tui.config import load_config
from uav_tui.errors import ConfigError
from uav_tui.web.rtp import Destination

pytestmark = pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="the receiver, Debian's ffmpeg, is not "
                                "installed (.ci/run installs it: apt-get install ffmpeg)")

SIZE = (320, 240)
MARK = (slice(100, 140), slice(140, 180))
"""Where the processor paints its marker, pure red, on every frame (rows, columns)."""


class Marks:
    """Paints a red square on each frame: the overlay the ground station must see."""

    def __init__(self) -> None:
        self.tmMgr = None

    def photo_processing(self, frame: Any) -> None:
        frame[MARK] = (0, 0, 255)


def receive(uri: str, frames: int, folder: Path) -> subprocess.Popen[bytes]:
    """FFmpeg listening on the port of ``uri`` (``udp://0.0.0.0:PORT``, as QGC takes it), ``frames`` BGR frames
    to stdout, each frame's stream time on stderr (``showinfo``'s ``pts_time:``)."""
    port = int(uri.rpartition(":")[2])
    sdp = folder / "stream.sdp"
    sdp.write_text(Destination("127.0.0.1", port).sdp())
    return subprocess.Popen(["ffmpeg", "-hide_banner", "-loglevel", "info", "-protocol_whitelist", "file,udp,rtp",
                             "-i", str(sdp), "-frames:v", str(frames), "-vf", "showinfo", "-f", "rawvideo",
                             "-pix_fmt", "bgr24", "-"],
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE)


async def test_the_ground_station_finds_the_stream_and_sees_the_overlay(tmp_path: Path) -> None:
    mavlink_port, video_port = free_port(socket.SOCK_DGRAM), free_port(socket.SOCK_DGRAM)
    core = make_core(web=False, source=f"synthetic:?width={SIZE[0]}&height={SIZE[1]}&fps=30",
                     processor="tests.web.test_ground_video:Marks", camera_mavlink=f"udpin:127.0.0.1:{mavlink_port}",
                     video_out=f"rtp://127.0.0.1:{video_port}", video_out_width=SIZE[0], video_out_fps=10)
    await core.start()
    station = GroundStation(mavlink_port)
    try:
        await station.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION)
        assert (await station.receive("CAMERA_INFORMATION")).flags & mavlink.CAMERA_CAP_FLAGS_HAS_VIDEO_STREAM
        await station.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION)
        info = await station.receive("VIDEO_STREAM_INFORMATION")
        assert info.type == mavlink.VIDEO_STREAM_TYPE_RTPUDP and info.encoding == mavlink.VIDEO_STREAM_ENCODING_H264
        assert info.uri == f"udp://0.0.0.0:{video_port}" and info.framerate == 10
        receiver = receive(info.uri, 20, tmp_path)
        out, err = await asyncio.get_running_loop().run_in_executor(None, receiver.communicate, None, 30)
        assert receiver.returncode == 0, err.decode(errors="replace")
        frames = np.frombuffer(out, np.uint8).reshape(-1, SIZE[1], SIZE[0], 3)
        assert len(frames) == 20
        for frame in frames:  # the processor's marker, through encoding: red inside, not red around it
            inside = frame[MARK].reshape(-1, 3).mean(axis=0)
            assert inside[2] > 200 and inside[:2].max() < 60, inside
            assert frame[MARK[0].start - 20, MARK[1].start - 20, 2] < 200
        # The configured 10 a second, by the stream's own clock (a wall-clock bound failed under load: the receiver
        # took 9.3 s to start, join at a key frame and decode 20 frames at load 8).
        stream_s = np.diff([float(t) for t in re.findall(rb"pts_time:([0-9.]+)", err)])
        assert len(stream_s) >= 10 and 0.08 <= float(np.median(stream_s)) <= 0.12, stream_s  # showinfo may miss one
        status = await station_status(station)
        assert status.framerate == 10 and (status.resolution_h, status.resolution_v) == SIZE
        video = core.side_channels.video
        assert video is not None and video.sent >= 20 and video.errors == 0
        sent = video.sent
        await asyncio.sleep(1.0)  # the receiver is gone: the stream goes on, it costs the platform nothing
        assert video.sent > sent and video.errors == 0 and core.worker is not None
    finally:
        station.sock.close()
        await core.stop("test finished")
    assert core.side_channels.video is None


async def station_status(station: GroundStation) -> Any:
    await station.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_STATUS)
    return await station.receive("VIDEO_STREAM_STATUS")


@pytest.mark.parametrize("uri", ["5600", "rtp://:5600", "rtsp://host:554/x", "rtp://host"],
                         ids=["port", "no host", "rtsp", "no port"])
def test_a_video_output_that_is_no_rtp_destination_is_refused_at_start(uri: str) -> None:
    with pytest.raises(ConfigError, match="video_out .* must be rtp://HOST:PORT"):
        load_config(None, {"video_out": uri})
