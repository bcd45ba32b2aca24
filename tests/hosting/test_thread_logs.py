"""With thread isolation the processor's log records reach the platform's handlers within a line budget, as its
prints do (and as both do from the processor's own process)."""

from __future__ import annotations

import asyncio
import logging
import threading
import time
from pathlib import Path

import pytest

from processors import load_processor
from sources import open_source
from tests.core.flight_helpers import wait_until
from uav_tui.config import load_config
from uav_tui.core import UavCore
from uav_tui.hosting.thread_host import ThreadHost
from uav_tui.hosting.thread_logs import ThreadLogBudget
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


SLEEPY = '''
import time

class Sleepy:
    def photo_processing(self, frame):
        time.sleep(0.5)
'''


async def test_a_stop_cancelled_while_it_waits_still_takes_the_budget_off(tmp_path: Path) -> None:
    """A second cancel (a loop shutting down) while the host waits for the processor's call: the filter left on the
    handlers judged a later thread's records (one with the same ident) and counted them nowhere."""
    (tmp_path / "sleepy.py").write_text(SLEEPY)
    source = open_source("synthetic:?width=160&height=120")
    host = ThreadHost(load_processor(f"{tmp_path}/sleepy.py:Sleepy"), lambda result: None)
    host.attach(source.buffer)
    try:
        task = asyncio.create_task(host.run())
        await wait_until(lambda: host.busy_s > 0, 10, "a call into the processor")
        task.cancel()
        await asyncio.sleep(0.05)  # the host now waits for the call to end
        task.cancel()
        await asyncio.gather(task, return_exceptions=True)
    finally:
        source.close()
    left = [f for h in logging.getLogger().handlers for f in h.filters if isinstance(f, ThreadLogBudget)]
    for handler in logging.getLogger().handlers:
        for stale in left:
            handler.removeFilter(stale)
    assert not left


async def test_a_budget_for_an_ended_thread_leaves_a_new_threads_records_alone() -> None:
    kept = Kept()
    root = logging.getLogger()
    root.addHandler(kept)
    ended = threading.Thread(target=lambda: None)
    budget = ThreadLogBudget(ended, lambda count: None)
    budget.install()
    try:
        ended.start()
        ended.join()
        time.sleep(0.05)  # until its stack is freed: glibc gives the next thread the same one, and its ident
        later = threading.Thread(target=lambda: [logging.getLogger("later").warning("%d", n) for n in range(50)])
        later.start()
        later.join()
    finally:
        budget.remove()
        root.removeHandler(kept)
    if later.ident != ended.ident:
        pytest.skip("this platform gave the new thread another ident: nothing to tell apart")
    assert len([record for record in kept.records if record.name == "later"]) == 50
