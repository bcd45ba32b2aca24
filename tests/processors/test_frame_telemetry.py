"""``self.tmMgr`` (FrameTelemetry): the frame's clock in ``snapshot()``, and ``save`` throttled by frame time."""

from __future__ import annotations

import dataclasses
import logging
import typing

import numpy as np
import pytest

from processors.frame_telemetry import FrameTelemetry, frame_time_s
from uav_values import Snapshot, Telemetry

IMAGE = np.zeros((480, 640, 3), np.uint8)


def test_the_snapshot_is_the_frames_telemetry_number_and_capture_time() -> None:
    tm = FrameTelemetry(lambda image, extra: None)
    tm.begin(7, 2_500_000_000, 1_700_000_000_000_000_000, {"rel_alt_m": 12.5, "armed": True}, 0.2)
    seen = tm.snapshot()
    assert (seen.frame_seq, seen.frame_t_ns, seen.frame_t_s, seen.frame_t_wall_ns) == (
        7, 2_500_000_000, 2.5, 1_700_000_000_000_000_000)
    assert (seen.rel_alt_m, seen.armed, seen.heartbeat_age_s) == (12.5, True, 0.2)
    assert tm.link_alive() and not tm.link_alive(0.1)
    assert frame_time_s(tm) == 2.5


def test_the_snapshot_is_a_frozen_record_with_every_field_typed() -> None:
    tm = FrameTelemetry(lambda image, extra: None)
    assert tm.snapshot() == Snapshot()  # before the first frame: nothing known, frame 0
    tm.begin(3, 100, 0, {"rel_alt_m": 4.0, "not_telemetry": 1}, None)  # a key that is no field is left out
    seen = tm.snapshot()
    assert type(seen) is Snapshot and seen.rel_alt_m == 4.0 and seen.pitch_deg is None
    with pytest.raises(dataclasses.FrozenInstanceError):
        seen.rel_alt_m = 5.0  # type: ignore[misc]
    hints = typing.get_type_hints(Snapshot)
    assert {f.name for f in dataclasses.fields(Snapshot)} == set(hints)  # every field has a type
    assert {f.name for f in dataclasses.fields(Telemetry)} < set(hints) and hints["rel_alt_m"] == float | None


def test_saves_faster_than_the_rate_are_dropped_by_frame_time_and_said_once(caplog: pytest.LogCaptureFixture) -> None:
    stored: list[dict] = []
    tm = FrameTelemetry(lambda image, extra: stored.append(extra), save_max_hz=2.0)
    with caplog.at_level(logging.WARNING, logger="processors.frame_telemetry"):
        for n in range(300):  # 10 s of a 30 FPS camera, saving every frame
            tm.begin(n + 1, round(n * 1e9 / 30), 0, {}, None)
            tm.save(IMAGE, n=n)
    # a burst of 2, then 2 a second of frame time: how fast the loop ran does not matter
    assert len(stored) == tm.saves == 2 + 20 - 1 and tm.saves_throttled == 300 - tm.saves
    assert [s["n"] for s in stored[:4]] == [0, 1, 15, 30]
    (warning,) = caplog.records
    assert warning.getMessage().startswith("tmMgr.save is called 30 times a second (640x480 frames): storing them "
                                           "all would fill about 6.3 GB an hour; storing at most 2 a second")


def test_no_limit_and_no_frame_clock_outside_a_host() -> None:
    stored = []
    tm = FrameTelemetry(lambda image, extra: stored.append(extra), save_max_hz=0)
    for _ in range(50):
        tm.save(IMAGE)
    assert len(stored) == 50 and tm.saves_throttled == 0
    with pytest.raises(TypeError, match="frame must be an image array, got str"):
        tm.save("not an image")
    assert isinstance(frame_time_s(None), float)  # a processor called directly: the monotonic clock
