"""The wire's encoding: what round-trips, and what a child's bytes may not smuggle in."""

from __future__ import annotations

import multiprocessing
import os
import struct
from multiprocessing.connection import wait

import msgspec
import numpy as np
import pytest

from uav_tui.hosting.codec import (
    INLINE,
    OUT_OF_BAND,
    TO_CHILD,
    Encoder,
    UnreadableResult,
    WireError,
    as_data,
    camera_message,
    camera_model,
    decode_from_child,
)
from uav_tui.hosting.pipe import Inbox, PipeCorrupt
from uav_tui.hosting.wire import Call, Camera, FrameOutcome, Reply, Result, ResultHead, Times
from uav_values.camera import CameraModel


def result(vector: object = None) -> Result:
    return Result(gen=3, released=("slot-a",), saves_throttled=0, outcome=FrameOutcome(1, 2, vector=vector), saves=())


def crafted(saves: list[object]) -> bytes:
    """A result as a child could send it, by hand: frame 3, slot-a released, times 1 and 2, these saves."""
    return msgspec.msgpack.encode([6, 3, ["slot-a"], 0, [1, 2, 0, None, {}, None, None, None, ""], saves])


def encoded(message: Result | Reply) -> bytes:
    return Encoder(out_of_band=True).encode(message)[0]


@pytest.mark.parametrize("model", [CameraModel.from_hfov(640, 480, 60), None], ids=["model", "none"])
def test_a_camera_model_reaches_the_child_as_it_was(model: CameraModel | None) -> None:
    message = TO_CHILD.decode(Encoder(out_of_band=False).encode(camera_message(7, model))[0])
    assert isinstance(message, Camera) and message.gen == 7
    assert camera_model(message) == model


def test_values_arrive_as_plain_data() -> None:
    vector = as_data((np.float32(0.5), 10**400, True), arrays=False)
    back = decode_from_child(encoded(result(vector)), [])
    assert isinstance(back, Result) and back.outcome.vector == (0.5, 10**400, True)  # a sequence arrives as a tuple
    assert as_data(np.zeros(3), arrays=False).startswith("array(")  # an array is no vector: its repr
    assert as_data(object()).startswith("<object object")


def ext(code: int, payload: object) -> msgspec.msgpack.Ext:
    return msgspec.msgpack.Ext(code, msgspec.msgpack.encode(payload))


@pytest.mark.parametrize("value, reason", [
    (ext(OUT_OF_BAND, (0, "|O", (1,))), "not a number type"),
    (ext(OUT_OF_BAND, (5, "|u1", (1,))), "was not sent"),
    (ext(OUT_OF_BAND, (0, "|u1", (2, 3))), "does not match"),
    (ext(INLINE, ("<f8", (1,), b"abc")), "does not match"),
    (ext(9, ()), "unknown extension type 9"),
], ids=["object dtype", "missing buffer", "wrong size", "short inline", "unknown kind"])
def test_an_array_that_is_not_one_is_the_frame_error(value: object, reason: str) -> None:
    data = crafted([[value, {}]])
    with pytest.raises(UnreadableResult, match=reason) as caught:
        decode_from_child(data, [bytearray(4)])
    assert caught.value.head == ResultHead(3, ("slot-a",), 0, Times(1, 2, 0))  # what frees the frame and counts it


def test_a_message_that_is_none_at_all_is_refused() -> None:
    for data in (b"\xc1", msgspec.msgpack.encode([99, 1]), msgspec.msgpack.encode({"gen": 1})):
        with pytest.raises(WireError):
            decode_from_child(data, [])


def test_a_reply_that_does_not_fit_keeps_its_call_id() -> None:
    data = msgspec.msgpack.encode([7, 12, True, 5, ["s"], {"a": ext(9, ())}, []])
    with pytest.raises(UnreadableResult) as caught:
        decode_from_child(data, [])
    assert caught.value.head.call_id == 12
    assert decode_from_child(encoded(Reply(12, True, 5, ("s",), {"a": [1]}, ())), []) == Reply(
        12, True, 5, ("s",), {"a": [1]}, ())


def nested(depth: int) -> bytes:
    return b"\x91" * depth + b"\xc0"  # [[[...[None]...]]]


@pytest.mark.parametrize("data, reason", [
    (b"\x96" + b"".join(msgspec.msgpack.encode(v) for v in (6, 3, ["slot-a"], 0)) + b"\x99"
     + b"".join(msgspec.msgpack.encode(v) for v in (1, 2, 0)) + nested(100_000)
     + b"".join(msgspec.msgpack.encode(v) for v in ({}, None, None, None, "", [])), "recursion limit|nested|depth"),
    (crafted([[ext(OUT_OF_BAND, (-1, "|u1", (4,))), {}]]), "was not sent"),
    (crafted([[ext(OUT_OF_BAND, (0, "|u1", (2**62, 4))), {}]]), "does not match"),
    (crafted([[ext(OUT_OF_BAND, (0, "<f8", (1, 1))), {}]]), "8-bit"),
    (crafted([[None, {"frame": 1}]]),
     "other than 'frame'"),
], ids=["deep", "negative buffer", "overflowing shape", "float image", "frame field"])
def test_what_a_hostile_child_crafts_is_that_frames_error(data: bytes, reason: str) -> None:
    with pytest.raises(WireError, match=reason):
        decode_from_child(data, [bytearray(8)])


def test_a_deep_or_circular_value_is_sent_as_text() -> None:
    circular: list[object] = []
    circular.append(circular)
    assert as_data(circular, arrays=False) == "[[...]]"
    deep: list[object] = []
    for _ in range(100_000):
        deep = [deep]
    assert isinstance(as_data(deep, arrays=False), str)


@pytest.mark.parametrize("frame, reason", [
    (struct.pack("!i", -2), "-2 bytes"), (struct.pack("!iQ", -1, 2**63), "bytes"),
    (struct.pack("!i", 8) + struct.pack("!I", 2**32 - 1) + b"\xc0\xc0\xc0\xc0", "out-of-band"),
], ids=["negative length", "huge length", "buffer count"])
def test_frames_no_sender_makes_end_the_pipe_and_allocate_nothing(frame: bytes, reason: str) -> None:
    ours, theirs = multiprocessing.Pipe()
    inbox = Inbox(ours)
    os.write(theirs.fileno(), frame)
    assert wait([inbox], timeout=10)
    with pytest.raises(PipeCorrupt, match=reason):
        inbox.read()
    inbox.close()
    ours.close()
    theirs.close()


def test_an_roi_reaches_catch_cmd_as_a_tuple() -> None:
    message = TO_CHILD.decode(Encoder(out_of_band=False).encode(Call(1, "catch_cmd", ((10, 20, 30, 40),)))[0])
    assert message.args == ((10, 20, 30, 40),) and type(message.args[0]) is tuple
