"""The frame buffer between a camera and its readers: counts what nobody read, stamps every frame."""

from __future__ import annotations

import time

import numpy as np

from sources.buffer import FrameBuffer


def test_frame_buffer_counts_overwrites_and_stamps() -> None:
    buffer = FrameBuffer()
    image = np.zeros((2, 2, 3), np.uint8)
    first = buffer.put(image)
    buffer.put(image)
    third = buffer.put(image)
    assert (buffer.captured, buffer.overwritten) == (3, 2)
    assert buffer.latest() is third and third.seq == 3
    assert third.t_mono_ns >= first.t_mono_ns and abs(third.t_wall_ns - time.time_ns()) < 1e9
    buffer.put(image)
    assert buffer.overwritten == 2  # the third frame was read before the fourth replaced it
    assert buffer.wait_newer(4, timeout=0.01) is None
    assert buffer.wait_newer(3, timeout=0.01).seq == 4


def test_a_frame_marked_read_after_newer_ones_came_is_not_counted_overwritten() -> None:
    buffer = FrameBuffer()
    image = np.zeros((2, 2, 3), np.uint8)
    buffer.put(image)  # taken by another process (peek), which says so only once it is done with it
    buffer.put(image)
    buffer.put(image)
    assert buffer.overwritten == 2  # as far as anyone knows yet
    buffer.mark_read(1)
    assert buffer.overwritten == 1  # only frame 2 was never taken
    assert not buffer.wait_read(timeout=0.01)  # the newest, 3, is still unread
    buffer.mark_read(3)
    assert buffer.overwritten == 1 and buffer.wait_read(timeout=0.01)
