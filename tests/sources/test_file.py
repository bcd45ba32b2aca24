"""file: replays a clip in a loop at the clip's frame rate."""

from __future__ import annotations

import statistics
import time

import pytest

from sources import create_source, open_source
from sources.buffer import FrameBuffer
from uav_tui.errors import SourceError


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
