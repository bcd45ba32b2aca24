"""Adding an output (docs/architecture.md, "Adding an output"): the test-only ``mark`` output of
:mod:`tests.relays.mark_output`, built only from the recipe's parts, works through a real core on ``--fc sim``: read
from the processor, relayed while autonomy is on, said in frames.csv, counted in the status, closed at the exit. No
edit to ``core.py``, ``status.py``, ``recording/rows.py`` or ``hosting/host.py``."""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from processors.outputs import FrameOutputs
from sources.buffer import Frame
from tests.core.flight_helpers import steering_config, wait_until
from tests.relays.mark_output import ENTRY, Mark, MarkRelay, register
from uav_tui.core import UavCore
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.wire import FrameOutcome
from uav_tui.relays.registry import consider_all

MARKING_PROCESSOR = '''
from tests.relays.mark_output import Mark


class Marking:
    """Test processor: marks the frame's centre."""

    def __init__(self):
        self.tmMgr = None

    def photo_processing(self, frame):
        self.centre = Mark(frame.shape[1] // 2, frame.shape[0] // 2)

    def getMark(self):
        return self.centre
'''


@pytest.mark.timeout(90)
async def test_a_registered_output_is_relayed_said_and_counted_through_a_real_core(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    register(monkeypatch)
    (tmp_path / "marking.py").write_text(MARKING_PROCESSOR)
    run_dir = tmp_path / "runs"
    core = UavCore(steering_config(tmp_path, processor=f"{tmp_path / 'marking.py'}:Marking", isolation="thread",
                                   record=True, runs_dir=str(run_dir)))
    await core.start()
    try:
        relay = core.relays["mark"]
        assert isinstance(relay, MarkRelay)  # the simulated controller has the capability
        assert "getMark" in core.status().capabilities
        await wait_until(lambda: core.last is not None and core.last.relayed.get("mark") == "not sent: autonomy off",
                         20, "a mark judged")
        assert relay.marked == []
        await core.execute("autonomy on")
        await wait_until(lambda: core.status().relayed["mark"]["sent"] >= 5, 20, "marks sent")
        assert relay.marked[0] == Mark(80, 60)  # the synthetic camera's 160 x 120 frame
        await core.execute("autonomy off")
        assert relay.stops  # told when autonomy stopped
    finally:
        await core.stop()
    assert relay.closed
    frames = pd.read_csv(next(run_dir.rglob("frames.csv")), keep_default_na=False)
    said = {json.loads(cell)["mark"] for cell in frames["relayed"] if cell}
    assert said == {"sent", "not sent: autonomy off"}


def test_without_the_capability_the_entry_s_stand_in_says_so() -> None:
    stand_in = ENTRY.absent(None)  # type: ignore[arg-type]  # the stand-in reads nothing of the core
    frame = Frame(np.zeros((4, 4, 3), np.uint8), 1, time.monotonic_ns(), time.time_ns())
    result = ProcessedFrame(frame, FrameOutcome(0, 0, outputs=FrameOutputs(more={"mark": Mark(2, 2)})))
    assert consider_all({"mark": stand_in}, result) == {"mark": "not sent: the flight controller has no heartbeat"}
    assert stand_in.counts == {}


def test_a_registered_output_never_shadows_a_built_in_one() -> None:
    outputs = FrameOutputs(more={"gimbal": {"mode": "rate"}, "mark": Mark(1, 1)})  # as a hostile process could send
    assert outputs.get("gimbal") is None and outputs.get("mark") == Mark(1, 1) and outputs.get("other") is None
