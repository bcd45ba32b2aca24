"""What native libraries write on fd 2 becomes events, bounded, and Python's own stderr still reaches the terminal."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import sys
import threading
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.videos import damaged_aerial_video
from uav_tui.events import Event, EventLog
from uav_tui.output.line_budget import BURST_LINES
from uav_tui.output.native_stderr import ORIGIN, native_stderr_as_events


def collect(events: EventLog) -> list[Event]:
    seen: list[Event] = []
    events.add_listener(seen.append)
    return seen


def decode_all(path: Path) -> int:
    capture = cv2.VideoCapture(str(path))
    frames = 0
    while capture.read()[0]:
        frames += 1
    capture.release()
    return frames


async def test_ffmpeg_complaints_about_a_damaged_real_video_are_events_not_terminal_text(
        tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    video = damaged_aerial_video(tmp_path)
    events = EventLog()
    events.bind(asyncio.get_running_loop())
    seen = collect(events)
    with native_stderr_as_events(events):
        frames = await asyncio.to_thread(decode_all, video)  # FFmpeg writes on fd 2 from the decoding thread
        print("a Python line", file=sys.stderr, flush=True)
        logging.getLogger("test").warning("a log record")
        await asyncio.sleep(0.2)
    assert frames == 237  # damaged, yet every frame decodes
    lines = [e for e in seen if e.origin == ORIGIN]
    assert lines and all(e.kind == "platform" and e.level == "warning" for e in lines)
    assert any(e.message.startswith("native library: [mpeg4 @ 0x") for e in lines), [e.message for e in lines]
    err = capfd.readouterr().err
    assert "[mpeg4 @" not in err  # before: every complaint went to the terminal, over the dashboard
    assert "a Python line" in err  # Python's own stderr still reaches it


async def test_libjpeg_on_a_cut_jpeg_as_a_usb_camera_sends_it_is_an_event(tmp_path: Path) -> None:
    video = damaged_aerial_video(tmp_path)
    ok, image = cv2.VideoCapture(str(video)).read()
    assert ok
    jpeg = cv2.imencode(".jpg", image)[1].tobytes()
    cut = np.frombuffer(jpeg[:len(jpeg) // 2] + jpeg[-2:], np.uint8)  # half a frame, as a USB hiccup leaves it
    events = EventLog()
    events.bind(asyncio.get_running_loop())
    seen = collect(events)
    with native_stderr_as_events(events):
        assert cv2.imdecode(cut, cv2.IMREAD_COLOR) is not None
        await asyncio.sleep(0.2)
    assert [e.message for e in seen] == ["native library: Corrupt JPEG data: premature end of data segment"]


async def test_a_flood_is_bounded_and_never_makes_the_writer_wait(tmp_path: Path) -> None:
    events = EventLog()
    events.bind(asyncio.get_running_loop())
    seen = collect(events)
    written = threading.Event()

    def flood() -> None:  # as a decoder on a lossy stream: a line per damaged block, as fast as it goes
        for n in range(20_000):
            # The pipe is full while the loop is busy: the line is lost, not waited for.
            with contextlib.suppress(BlockingIOError):
                os.write(2, f"[h264 @ 0x1] error while decoding MB {n} \x1b[2J\n".encode())
        written.set()

    with native_stderr_as_events(events):
        writer = threading.Thread(target=flood)
        writer.start()
        writer.join(timeout=30)  # the loop is blocked here: nobody reads the pipe meanwhile
        assert written.is_set()
        await asyncio.sleep(1.5)  # the count comes once the limit allows, not only at the end
        messages = [e.message for e in seen if e.origin == ORIGIN]
    assert len(seen) == len(messages)
    assert len(messages) == BURST_LINES + 1
    assert all("\x1b" not in m and "\\x1b[2J" in m for m in messages[:-1])  # escaped: it cannot clear the screen
    assert messages[-1].startswith("native library: ") and messages[-1].endswith("more lines left out (too many "
                                                                                 "at once)")


async def test_what_is_held_back_is_emitted_before_the_record_closes() -> None:
    # Under load a flood's count came from its timer after the run's events.csv had closed: printed, not recorded.
    events = EventLog()
    events.bind(asyncio.get_running_loop())
    seen = collect(events)
    with native_stderr_as_events(events):
        for n in range(BURST_LINES + 5):
            os.write(2, f"[mpeg4 @ 0x1] damaged block {n}\n".encode())
        events.emit_held()  # no loop turn since: the pipe was not read yet, and the count's timer is 1 s away
        held = [e.message for e in seen]
        await asyncio.sleep(1.2)
    assert held[:BURST_LINES] == [f"native library: [mpeg4 @ 0x1] damaged block {n}" for n in range(BURST_LINES)]
    assert held[BURST_LINES:] == ["native library: 5 more lines left out (too many at once)"]
    assert len(seen) == len(held)  # said once


async def test_everything_is_put_back_after(capfd: pytest.CaptureFixture[str]) -> None:
    stderr, dunder = sys.stderr, sys.__stderr__
    handler = logging.StreamHandler(sys.__stderr__)
    logging.getLogger().addHandler(handler)
    try:
        with native_stderr_as_events(EventLog()):
            assert handler.stream is not dunder and sys.__stderr__ is not dunder
        assert (sys.stderr, sys.__stderr__, handler.stream) == (stderr, dunder, dunder)
    finally:
        logging.getLogger().removeHandler(handler)
    os.write(2, b"native again\n")
    assert "native again" in capfd.readouterr().err
