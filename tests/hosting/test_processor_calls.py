"""The operator's calls into a hung processor (issue 42 point 9): none waits its own full timeout behind it."""

from __future__ import annotations

import asyncio
import time
from pathlib import Path

import pytest

from uav_tui.config import load_config
from uav_tui.core import UavCore
from uav_tui.errors import UavError

HANGS_ON_F1 = '''
import time


class HangsOnF1:
    """F1 hangs for 4 s; every F-key it gets is written to a file."""

    def __init__(self, log):
        self.tmMgr = None
        self.log = log

    def photo_processing(self, frame):
        pass

    def customize_processing(self, id):
        with open(self.log, "a") as out:
            out.write(f"{id}\\n")
        if id == 1:
            time.sleep(4)
'''

TIMEOUT_S = 2.0


async def f_key(core: UavCore, n: int) -> tuple[float, str]:
    """``f N`` through the core: (when it ended, monotonic s; what it said)."""
    try:
        said = await core.execute(f"f {n}")
    except UavError as exc:
        said = str(exc)
    return time.monotonic(), said


@pytest.mark.parametrize("isolation", ["process", "thread"])
async def test_a_second_f_behind_a_hung_one_fails_with_it_and_is_never_sent(tmp_path: Path, isolation: str) -> None:
    (tmp_path / "hangs.py").write_text(HANGS_ON_F1)
    log = tmp_path / "keys.txt"
    core = UavCore(load_config(None, {
        "source": "synthetic:?width=160&height=120", "fc": "none", "record": False, "isolation": isolation,
        "processor": f"{tmp_path / 'hangs.py'}:HangsOnF1", "processor_args": {"log": str(log)},
        "processor_call_timeout": TIMEOUT_S, "processor_timeout": 30}))
    await core.start()
    try:
        first = asyncio.create_task(f_key(core, 1))
        await asyncio.sleep(0.8)
        second = asyncio.create_task(f_key(core, 2))
        (first_end, first_said), (second_end, second_said) = await asyncio.gather(first, second)
        assert f"did not return within {TIMEOUT_S:g} s" in first_said
        assert second_end - first_end < 0.4, second_said  # given up with it, not 0.8 s later on its own clock
        assert "customize_processing(2,) not sent" in second_said and "customize_processing(1,)" in second_said
        asked = time.monotonic()
        third_end, third_said = await f_key(core, 3)  # while F1 still hangs: refused at once
        assert third_end - asked < 0.5 and "has not returned from" in third_said
        await asyncio.sleep(5.5 - (time.monotonic() - first_end + TIMEOUT_S))  # F1 (4 s) has returned by now
        assert (await f_key(core, 4))[1] == "F4: HangsOnF1.customize_processing(4) done"
        assert log.read_text().split() == ["1", "4"]  # F2 and F3 never reached the processor
    finally:
        await core.stop("test finished")
