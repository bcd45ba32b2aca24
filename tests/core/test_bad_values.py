"""Bad values from a processor: bounded text, counted once, recorded, never a traceback (issue 14, 5-6)."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from tests.core.flight_helpers import wait_until
from uav_tui.config import load_config
from uav_tui.core import UavCore
from uav_tui.events import MAX_MESSAGE_CHARS
from uav_tui.recorded import dataset

BAD_PROCESSOR = '''
HUGE = tuple(range(10**6))

class Bad:
    """The first 15 frames: a million-element vector; then a number no float can hold; then an exception."""

    def __init__(self):
        self.tmMgr = None
        self.frames = 0

    def photo_processing(self, frame):
        self.frames += 1
        if self.frames > 30:
            raise ValueError("x" * 10**6 + "\\x1b[2J")

    def getPreparedVector(self):
        return HUGE if self.frames <= 15 else (10**400, 0, 1)
'''


async def test_huge_and_overflowing_vectors_are_described_briefly_counted_and_recorded(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    (tmp_path / "bad.py").write_text(BAD_PROCESSOR)
    config = load_config(None, {"source": "synthetic:?width=160&height=120&fps=30", "processor":
                                f"{tmp_path / 'bad.py'}:Bad", "runs_dir": str(tmp_path / "runs")})
    core = UavCore(config)
    caplog.set_level(logging.ERROR, logger="asyncio")
    await core.start()
    try:
        await wait_until(lambda: core.worker.stats.errors >= 10, 30, "40 frames")
    finally:
        await core.stop("test finished")
    assert not [r for r in caplog.records if r.name == "asyncio"], "a callback on the loop raised"
    assert core.gate.rejected == 30  # every vector, none lost to an exception
    rejections = [e.message for e in core.events.recent  # not the start line saying the envelope in force
                  if e.kind == "autonomy" and not e.message.startswith("envelope: ")]
    assert len(rejections) == 3, rejections  # each kind said once, then how often it repeated
    assert "(0, 1, 2, 3, ...) (1000000 items)" in rejections[0] and len(rejections[0]) < 200
    assert "the previous message repeated 14 more times" in rejections[1]
    assert "too large for a float" in rejections[2] and len(rejections[2]) < 200
    errors = [e.message for e in core.events.recent  # not "loading processor ... (5 s ...)", when slow to start
              if e.kind == "processor" and not e.message.startswith("loading processor")]
    assert len(errors[0]) < MAX_MESSAGE_CHARS + 100 and errors[0].startswith("frame ")  # in full once, then counted
    assert all(m.startswith("photo_processing raised ValueError ") for m in errors[1:]), errors
    assert all(len(m) < 1000 for m in errors[1:]) and not [m for m in errors if "\x1b" in m]

    run = dataset.load(core.recorder.run_dir)
    decisions = run.frames.decision.tolist()
    assert len(decisions) >= 40
    assert all(d.startswith("rejected") for d in decisions[:30]) and decisions[30:].count("error") >= 10
    size = sum(f.stat().st_size for f in core.recorder.run_dir.rglob("*") if f.is_file())
    assert size < 2_000_000
