"""The processed video as an RTSP stream (GStreamer's RTSP server), announced by the MAVLink camera component.

FFmpeg's own command-line tool (Debian's ``ffmpeg``) plays the URI the camera component announces, over TCP as
QGC asks for it, and hands the decoded frames to the test; one receiver is killed mid-stream, the next one plays.
"""

from __future__ import annotations

import asyncio
import shutil
import socket
import subprocess
from itertools import pairwise
from typing import Any

import numpy as np
import pytest
from pymavlink.dialects.v20 import common as mavlink

from tests.web.conftest import free_port, make_core
from tests.web.test_camera_tracking import GroundStation
from tests.web.test_ground_video import MARK, SIZE, Marks
from uav_tui.config import load_config
from uav_tui.errors import ConfigError
from uav_tui.web.ground_video import GroundVideo


def _rtsp_server_missing() -> str | None:
    if shutil.which("ffmpeg") is None:
        return "the receiver, Debian's ffmpeg, is not installed (.ci/run installs it)"
    try:
        from uav_tui.web.rtsp import gstreamer

        gstreamer()
    except ConfigError as exc:
        return f"{exc} (.ci/run installs it)"
    return None


pytestmark = pytest.mark.skipif(bool(_rtsp_server_missing()), reason=str(_rtsp_server_missing()))


BITS, BLOCK = 8, 20
"""The frame's number, drawn as 8 black or white 20 px blocks along the top."""


class Counts(Marks):
    """The red square, and each frame's number along the top: a picture that changes in every slice of every frame
    (a decoder that lost part of a frame shows the part before)."""

    def __init__(self) -> None:
        super().__init__()
        self.frames = 0

    def photo_processing(self, frame: Any) -> None:
        super().photo_processing(frame)
        self.frames += 1
        for bit in range(BITS):
            frame[:BLOCK, bit * BLOCK:(bit + 1) * BLOCK] = 255 if self.frames >> bit & 1 else 0


def number(frame: np.ndarray) -> int:
    means = frame[4:BLOCK - 4, :BITS * BLOCK].reshape(BLOCK - 8, BITS, BLOCK, 3)[:, :, 4:BLOCK - 4].mean(axis=(0, 2, 3))
    return sum(1 << bit for bit in range(BITS) if means[bit] > 128)


def play(uri: str, frames: int | None) -> subprocess.Popen[bytes]:
    """FFmpeg playing ``uri`` over TCP: ``frames`` BGR frames to stdout, each decoded frame once (None: decodes them
    for nothing until killed). Without ``-fps_mode passthrough`` the rawvideo output is filled to a constant rate:
    under load a late frame came out three times."""
    output = (["-frames:v", str(frames), "-fps_mode", "passthrough", "-f", "rawvideo", "-pix_fmt", "bgr24"] if frames
              else ["-f", "null"])
    return subprocess.Popen(["ffmpeg", "-hide_banner", "-loglevel", "error", "-rtsp_transport", "tcp", "-i", uri,
                             *output, "-"], stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE)


async def decoded(receiver: subprocess.Popen[bytes]) -> np.ndarray:
    out, err = await asyncio.get_running_loop().run_in_executor(None, receiver.communicate, None, 30)
    assert receiver.returncode == 0, err.decode(errors="replace")
    return np.frombuffer(out, np.uint8).reshape(-1, SIZE[1], SIZE[0], 3)


def assert_marked(frames: np.ndarray) -> None:
    for frame in frames:  # the processor's marker, through encoding: red inside, not red around it
        inside = frame[MARK].reshape(-1, 3).mean(axis=0)
        assert inside[2] > 200 and inside[:2].max() < 60, inside
        assert frame[MARK[0].start - 20, MARK[1].start - 20, 2] < 200
    # Each a newer frame than the one before. Not "within a second" (30 of the camera's frames): with both cores
    # loaded by busy loops one step was longer, though every frame was newer.
    numbers = [number(frame) for frame in frames]
    assert all(0 < (b - a) % 2**BITS < 2 ** (BITS - 1) for a, b in pairwise(numbers)), numbers


async def until(check: Any, timeout_s: float = 10.0) -> None:
    async with asyncio.timeout(timeout_s):
        while not check():
            await asyncio.sleep(0.05)


async def test_a_ground_station_plays_the_announced_rtsp_stream_and_a_killed_one_costs_nothing() -> None:
    mavlink_port, video_port, rtsp_port = free_port(socket.SOCK_DGRAM), free_port(socket.SOCK_DGRAM), free_port()
    core = make_core(web=False, source=f"synthetic:?width={SIZE[0]}&height={SIZE[1]}&fps=30",
                     processor="tests.web.test_rtsp_video:Counts", camera_mavlink=f"udpin:127.0.0.1:{mavlink_port}",
                     video_out=f"rtp://127.0.0.1:{video_port}", video_rtsp_port=rtsp_port, video_rtsp_path="/live/uav",
                     video_out_width=SIZE[0], video_out_fps=10)
    await core.start()
    station = GroundStation(mavlink_port)
    try:
        rtsp = core.side_channels.rtsp
        assert isinstance(rtsp, GroundVideo)
        await until(lambda: rtsp.unsent >= 5)  # no client: nothing encoded, each frame counted
        assert rtsp.sent == 0 and not rtsp.target.watched
        await station.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION, 0)
        streams = [await station.receive("VIDEO_STREAM_INFORMATION") for _ in range(2)]
        assert [(s.stream_id, s.count) for s in streams] == [(1, 2), (2, 2)]
        udp, info = streams
        assert udp.type == mavlink.VIDEO_STREAM_TYPE_RTPUDP and udp.uri == f"udp://0.0.0.0:{video_port}"
        assert info.type == mavlink.VIDEO_STREAM_TYPE_RTSP and info.encoding == mavlink.VIDEO_STREAM_ENCODING_H264
        assert info.uri == f"rtsp://127.0.0.1:{rtsp_port}/live/uav" and info.framerate == 10

        assert_marked(await decoded(play(info.uri, 20)))
        assert rtsp.sent >= 20 and rtsp.errors == 0

        killed = play(info.uri, None)  # plays until killed mid-stream, no TEARDOWN
        await until(lambda: rtsp.target.watched)
        sent = rtsp.sent
        await until(lambda: rtsp.sent >= sent + 10)
        killed.kill()
        killed.communicate()
        await until(lambda: not rtsp.target.watched)  # its session ends with its connection
        sent, video_sent = rtsp.sent, core.side_channels.video.sent if core.side_channels.video else 0
        await asyncio.sleep(1.0)
        assert rtsp.sent == sent and rtsp.errors == 0 and core.worker is not None
        assert core.side_channels.video is not None and core.side_channels.video.sent > video_sent  # RTP goes on

        assert_marked(await decoded(play(info.uri, 10)))  # the next ground station plays again
        await station.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_STATUS, 2)
        status = await station.receive("VIDEO_STREAM_STATUS")
        assert status.stream_id == 2 and (status.resolution_h, status.resolution_v) == SIZE
        await station.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION, 3)
        ack = await station.receive("COMMAND_ACK", command=mavlink.MAV_CMD_REQUEST_MESSAGE)
        assert ack.result == mavlink.MAV_RESULT_DENIED  # there is no third stream
    finally:
        station.sock.close()
        await core.stop("test finished")
    assert core.side_channels.rtsp is None


def test_a_closed_server_frees_its_port_for_the_next_start() -> None:
    from uav_tui.web.rtsp import RtspServer

    first = RtspServer(0, "/video", "127.0.0.1")
    first.close()
    again = RtspServer(first.port, "/video", "127.0.0.1")  # a core restarted in the same process (the TUI)
    assert again.port == first.port
    again.close()
    again.close()  # idempotent


@pytest.mark.parametrize("path", ["video", "/", "/a b", "/x/"], ids=["no slash", "empty", "space", "trailing"])
def test_an_rtsp_path_that_is_no_path_is_refused_at_start(path: str) -> None:
    with pytest.raises(ConfigError, match="video_rtsp_path .* must be a path such as /video"):
        load_config(None, {"video_rtsp_path": path})
