"""file: replays a clip in a loop at the clip's frame rate."""

from __future__ import annotations

import itertools
import logging
import os
import statistics
import sys
import threading
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from sources import create_source, decoder_threads, open_source
from sources.buffer import FrameBuffer
from sources.file import NICENESS, FileSource
from uav_tui.errors import SourceError
from uav_tui.evaluation import find_sequences

CLIP_FRAMES = 10


def _collect(buffer: FrameBuffer, duration_s: float) -> list[tuple[int, int]]:
    """(seq, capture monotonic ns) of every frame the reader saw in ``duration_s``."""
    seen, seq, end = [], 0, time.monotonic() + duration_s
    while time.monotonic() < end:
        frame = buffer.wait_newer(seq, timeout=1)
        if frame is None:
            break
        seq = frame.seq
        seen.append((frame.seq, frame.t_mono_ns))
    return seen


def test_loops_at_end_of_file(video_file) -> None:
    source = open_source(f"file:{video_file(frames=6, fps=30)}?realtime=0")
    try:
        seq = 0
        while seq < 20:  # a reader taking every frame
            frame = source.buffer.wait_newer(seq, timeout=10)
            assert frame is not None
            seq = frame.seq
        props = source.get_properties()
        assert props["frame_count"] == 6
        assert props["loops"] >= 3
        assert props["stalled_since"] is None and props["last_error"] is None
    finally:
        source.close()


def test_paces_at_the_file_frame_rate(video_file) -> None:
    source = open_source(f"file:{video_file(frames=40, fps=20)}")
    try:
        assert source.get_properties()["fps"] == pytest.approx(20)
        seen = _collect(source.buffer, 1.2)
    finally:
        source.close()
    # Capture timestamps come from the capture thread, so a slow reader does not distort them.
    intervals_ms = [(t1 - t0) / 1e6 for (s0, t0), (s1, t1) in zip(seen, seen[1:], strict=False) if s1 == s0 + 1]
    assert len(intervals_ms) >= 10
    assert statistics.median(intervals_ms) >= 35  # 50 ms per frame: paced, not as fast as it decodes
    (first_seq, first_t), (last_seq, last_t) = seen[0], seen[-1]
    assert (last_t - first_t) / 1e6 / (last_seq - first_seq) >= 40  # never faster than the file on average


def test_realtime_off_delivers_faster_than_the_file_rate(video_file) -> None:
    clip = video_file(frames=20, fps=10)
    counts = {}
    for realtime in (1, 0):
        source = open_source(f"file:{clip}?realtime={realtime}")
        counts[realtime] = len(_collect(source.buffer, 0.5))
        source.close()
    assert counts[1] <= 8
    assert counts[0] > 3 * counts[1]


def test_realtime_off_replays_every_frame_in_lockstep_with_the_reader(video_file) -> None:
    source = open_source(f"file:{video_file(frames=12, fps=30)}?realtime=0")
    try:
        seqs = []
        for _ in range(30):  # a slow reader: the source waits for it instead of skipping frames
            frame = source.buffer.wait_newer(seqs[-1] if seqs else 0, timeout=5)
            assert frame is not None
            seqs.append(frame.seq)
            time.sleep(0.01)
        assert seqs == list(range(1, 31))
        assert source.get_properties()["frames_dropped"] == 0
        time.sleep(0.2)
        assert source.buffer.captured <= 31  # with no reader it decodes one frame ahead, then waits
    finally:
        source.close()


def test_resizes_to_the_requested_size(video_file) -> None:
    source = open_source(f"file:{video_file()}?width=80")
    try:
        assert source.get_frame_size() == (80, 60)
        frame = source.buffer.wait_newer(0, timeout=5)
        assert frame is not None and frame.image.shape == (60, 80, 3)
    finally:
        source.close()


def test_missing_file_names_the_path(tmp_path) -> None:
    with pytest.raises(SourceError, match="no such video file: .*nothing.mp4"):
        open_source(f"file:{tmp_path / 'nothing.mp4'}")


def test_corrupt_file_is_reported_not_raised_from_the_thread(tmp_path) -> None:
    bad = tmp_path / "broken.mp4"
    bad.write_bytes(b"\x00\x00\x00\x18ftypmp42" + bytes(range(256)) * 40)
    source = create_source(f"file:{bad}")
    assert source.open() is False
    assert "not a video FFmpeg can read" in source.get_properties()["last_error"]
    source.close()
    with pytest.raises(SourceError, match="cannot open camera"):
        open_source(f"file:{bad}")


@pytest.fixture
def aerial_clip(tmp_path: Path, aerial_tracking: Path) -> Path:
    """The first frames of a real drone video (the aerial-tracking set), 320x240, as an MP4 file."""
    path = tmp_path / "aerial.mp4"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"mp4v"), 30, (320, 240))
    for frame in itertools.islice(find_sequences([aerial_tracking])[0].frames(), CLIP_FRAMES):
        writer.write(cv2.resize(frame, (320, 240), interpolation=cv2.INTER_AREA))
    writer.release()
    return path


@pytest.fixture
def switch_every_few_frames(monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture) -> None:
    """The file source tries the other decoder thread count every 3 frames (instead of every 30 s)."""
    monkeypatch.setattr(decoder_threads, "WINDOW_S", 0.0)
    monkeypatch.setattr(decoder_threads, "MIN_FRAMES", 3)
    monkeypatch.setattr(decoder_threads, "RETRY_S", -1.0)
    caplog.set_level(logging.INFO, logger="sources.file")


def _replayed(uri: str, count: int) -> tuple[list[np.ndarray], dict]:
    source = open_source(uri)
    try:
        images, seq = [], 0
        while len(images) < count:
            frame = source.buffer.wait_newer(seq, timeout=5)
            assert frame is not None
            assert frame.seq == seq + 1  # a reader taking every frame of a realtime=0 replay misses none
            images.append(frame.image.copy())
            seq = frame.seq
        return images, source.get_properties()
    finally:
        source.close()


def _every_frame(path: Path) -> list[np.ndarray]:
    capture = cv2.VideoCapture(str(path), cv2.CAP_FFMPEG)
    frames = []
    while (frame := capture.read()[1]) is not None:
        frames.append(frame)
    capture.release()
    return frames


def _same_sequence(images: list[np.ndarray], clip: list[np.ndarray]) -> bool:
    return all(np.array_equal(image, clip[i % len(clip)]) for i, image in enumerate(images))


def test_switching_decoder_threads_mid_replay_neither_skips_nor_repeats_a_frame(
        aerial_clip: Path, switch_every_few_frames: None, caplog: pytest.LogCaptureFixture) -> None:
    images, props = _replayed(f"file:{aerial_clip}?realtime=0", 5 * CLIP_FRAMES)
    switches = [r.getMessage() for r in caplog.records if ": decoding on" in r.getMessage()]
    assert len(switches) >= 8, switches
    assert any("one thread" in s for s in switches) and any("FFmpeg's" in s for s in switches)
    assert any(s.endswith("from frame 0") for s in switches)  # one across the end of the file, too
    assert props["decoder_threads_adaptive"] and props["loops"] >= 4
    assert _same_sequence(images, _every_frame(aerial_clip))


def test_a_reopened_file_that_lands_on_another_frame_is_not_used(
        aerial_clip: Path, switch_every_few_frames: None, caplog: pytest.LogCaptureFixture,
        monkeypatch: pytest.MonkeyPatch) -> None:
    open_at = FileSource._open_at
    monkeypatch.setattr(FileSource, "_open_at", lambda self, threads, position: open_at(self, threads, position + 1))
    images, props = _replayed(f"file:{aerial_clip}?realtime=0", 3 * CLIP_FRAMES)
    assert _same_sequence(images, _every_frame(aerial_clip))
    assert props["decoder_threads"] == 1 and not props["decoder_threads_adaptive"]
    assert any("decodes another frame than the one due" in r.getMessage() for r in caplog.records)
    assert not any(": decoding on" in r.getMessage() for r in caplog.records)


def test_threads_fixes_the_decoder_thread_count(aerial_clip: Path, switch_every_few_frames: None) -> None:
    images, props = _replayed(f"file:{aerial_clip}?realtime=0&threads=0", 2 * CLIP_FRAMES)
    assert props["decoder_threads"] == "ffmpeg" and not props["decoder_threads_adaptive"]
    assert _same_sequence(images, _every_frame(aerial_clip))
    with pytest.raises(SourceError, match="threads=.-1. must be a number >= 0"):
        create_source(f"file:{aerial_clip}?threads=-1")


def _niceness(tid: int) -> int:
    return int(Path(f"/proc/self/task/{tid}/stat").read_text().rpartition(")")[2].split()[16])


def _decoder_threads() -> list[int]:
    """FFmpeg's threads in this process; one that ends between the listing and its name is not counted."""
    return [int(tid) for tid in os.listdir("/proc/self/task") if _thread_name(tid).startswith("av:")]


def _thread_name(tid: str) -> str:
    try:
        return Path(f"/proc/self/task/{tid}/comm").read_text()
    except FileNotFoundError:
        return ""  # the thread ended (another test's decoder, a pool's worker)


@pytest.mark.skipif(sys.platform != "linux", reason="per-thread priorities are Linux's")
def test_a_replay_decodes_at_a_lower_priority_than_the_platform(
        aerial_clip: Path, switch_every_few_frames: None, caplog: pytest.LogCaptureFixture) -> None:
    platform = _niceness(threading.get_native_id())
    source = open_source(f"file:{aerial_clip}?realtime=0")
    try:
        seq, deadline = 0, time.monotonic() + 10
        while not any("FFmpeg's" in r.getMessage() for r in caplog.records) and time.monotonic() < deadline:
            frame = source.buffer.wait_newer(seq, timeout=5)  # a reader taking every frame until a switch
            seq = frame.seq if frame is not None else seq
        assert source._thread is not None
        assert _niceness(source._thread.native_id) == min(19, platform + NICENESS)
        decoders = _decoder_threads()
        assert decoders, "FFmpeg started no decoder thread"
        assert {_niceness(tid) for tid in decoders} == {min(19, platform + NICENESS)}  # started by the capture thread
    finally:
        source.close()


@pytest.mark.skipif(sys.platform != "linux", reason="per-thread priorities are Linux's")
def test_a_fixed_thread_count_decodes_at_the_lower_priority_too(aerial_clip: Path) -> None:
    """``threads=2``: the file is opened (and FFmpeg's threads started) before the capture thread runs, on a thread
    at the decoding priority; opened on the caller's thread, they ran at the platform's."""
    platform = _niceness(threading.get_native_id())
    source = open_source(f"file:{aerial_clip}?realtime=0&threads=2")
    try:
        assert source.buffer.wait_newer(0, timeout=5) is not None
        decoders = _decoder_threads()
        assert decoders, "FFmpeg started no decoder thread"
        assert {_niceness(tid) for tid in decoders} == {min(19, platform + NICENESS)}
    finally:
        source.close()
