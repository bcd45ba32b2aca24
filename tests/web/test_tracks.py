"""The shared video track: scaling, pacing, one source for all viewers, nothing without a viewer."""

from __future__ import annotations

import asyncio
import time

import numpy as np
import pytest
from aiortc.mediastreams import MediaStreamError

from sources.buffer import Frame
from uav_tui.flight.autonomy import NO_DECISION
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.wire import FrameOutcome
from uav_tui.relays.contract import HandledFrame
from uav_tui.web.tracks import ProcessedVideoTrack, VideoHub, to_video_frame


def processed(seq: int, width: int = 640, height: int = 480) -> HandledFrame:
    image = np.full((height, width, 3), seq % 256, dtype=np.uint8)
    return HandledFrame(ProcessedFrame(Frame(image, seq, time.monotonic_ns(), time.time_ns()), FrameOutcome(0, 0)),
                        NO_DECISION)


@pytest.mark.parametrize(("size", "width", "expected"), [
    ((640, 480), 640, (640, 480)), ((1280, 720), 640, (640, 360)), ((320, 240), 640, (320, 240)),
    ((1001, 501), 641, (640, 320)),
], ids=["same", "down", "never-up", "even"])
def test_to_video_frame_scales_down_to_even_sizes(size: tuple[int, int], width: int,
                                                  expected: tuple[int, int]) -> None:
    image = np.zeros((size[1], size[0], 3), dtype=np.uint8)
    image[:, :, 2] = 255  # red in BGR
    frame = to_video_frame(image, width)
    assert (frame.width, frame.height) == expected and frame.format.name == "yuv420p"
    rgb = frame.to_ndarray(format="rgb24")
    assert rgb[..., 0].mean() > 200 and rgb[..., 2].mean() < 60  # the colour survives the single conversion


async def test_track_sends_each_new_frame_once_and_paces_itself() -> None:
    track = ProcessedVideoTrack(width=320, fps=5)
    track.offer(processed(1))
    first = await track.recv()
    assert (first.width, first.height) == (320, 240)
    with pytest.raises(TimeoutError):  # nothing new: nothing is sent again
        await asyncio.wait_for(track.recv(), 0.3)
    started = time.monotonic()
    stamps = [first.pts]
    for seq in range(2, 5):
        track.offer(processed(seq))
        stamps.append((await track.recv()).pts)
    assert time.monotonic() - started >= 2 * 0.2  # at most 5 per second
    assert stamps == sorted(set(stamps))
    track.stop()
    with pytest.raises(MediaStreamError):
        await track.recv()


class FakeCore:
    def __init__(self) -> None:
        self.listeners: list = []

    def add_frame_listener(self, listener) -> None:
        self.listeners.append(listener)

    def remove_frame_listener(self, listener) -> None:
        self.listeners.remove(listener)


async def test_hub_shares_one_source_and_stops_with_the_last_viewer() -> None:
    core = FakeCore()
    hub = VideoHub(core, width=320, fps=30)
    assert core.listeners == [] and hub.source is None
    a, b = hub.subscribe(), hub.subscribe()
    assert hub.viewers == 2 and len(core.listeners) == 1
    source = hub.source
    for listener in core.listeners:
        listener(processed(1))
    frame_a, frame_b = await asyncio.wait_for(asyncio.gather(a.recv(), b.recv()), 5)
    assert frame_a is frame_b  # converted once, relayed to both
    assert source.sent == 1
    hub.unsubscribe(a)
    assert hub.source is source and len(core.listeners) == 1
    hub.unsubscribe(b)
    assert hub.source is None and core.listeners == [] and source.readyState == "ended"
    await asyncio.sleep(0.05)  # the relay's reader sees the end and finishes
