"""With thread isolation the processor's log records reach the platform's handlers within a line budget, as its
prints do (and as both do from the processor's own process)."""

from __future__ import annotations

import logging
from pathlib import Path

from tests.core.flight_helpers import wait_until
from uav_tui.config import load_config
from uav_tui.core import UavCore
from uav_tui.output.line_budget import BURST_LINES

CHATTY = '''
import logging

class Chatty:
    def __init__(self):
        self.frames = 0

    def photo_processing(self, frame):
        self.frames += 1
        for n in range(100):
            logging.getLogger("chatty").warning("frame %d record %d", self.frames, n)
'''


class Kept(logging.Handler):
    def __init__(self) -> None:
        super().__init__()
        self.records: list[logging.LogRecord] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)


async def test_a_flood_of_log_records_is_cut_to_the_budget_and_counted(tmp_path: Path) -> None:
    (tmp_path / "chatty.py").write_text(CHATTY)
    kept = Kept()
    root = logging.getLogger()
    root.addHandler(kept)
    core = UavCore(load_config(None, {"source": "synthetic:?width=160&height=120", "fc": "none", "record": False,
                                      "processor": f"{tmp_path}/chatty.py:Chatty", "isolation": "thread"}))
    try:
        await core.start()
        try:
            await wait_until(lambda: core.worker is not None and core.worker.stats.frames_processed >= 5, 10,
                             "5 frames")
            logging.getLogger("not.the.processor").warning("said on the loop meanwhile")
        finally:
            await core.stop()
    finally:
        root.removeHandler(kept)
    chatty = [record for record in kept.records if record.name == "chatty"]
    assert BURST_LINES <= len(chatty) <= BURST_LINES + 5, len(chatty)  # the burst, then about one a second
    said = [e.message for e in core.events.recent if "log records" in e.message]
    assert said and "left out" in said[0], said
    assert any(record.name == "not.the.processor" for record in kept.records)  # other threads' records pass
