"""The core loads the processor and connects the vehicle at once: the part that fails says so, and the part that
did start is released with it (no processor process, no simulator left behind); so are both when the wiring of the
parts after them fails."""

from __future__ import annotations

import contextlib
from pathlib import Path

import psutil
import pytest

from controllers.errors import ConnectError
from processors.errors import ProcessorLoadError
from tests.core.flight_helpers import wait_until
from tests.flight.test_envelope import polygon_file
from uav_tui.config import Config, with_overrides
from uav_tui.core import UavCore
from uav_tui.errors import ConfigError

SLOW_PROCESSOR = '''
import time

class Slow:
    """Loads for a second: the vehicle's failure comes while its process is still starting."""

    def __init__(self):
        time.sleep(1.0)

    def photo_processing(self, frame):
        pass
'''


def config(tmp_path: Path, **overrides: str) -> Config:
    processor = tmp_path / "slow.py"
    processor.write_text(SLOW_PROCESSOR)
    return with_overrides(Config(), source="synthetic:?width=160&height=120", processor=f"{processor}:Slow",
                          record=False, **overrides)


def children() -> set[int]:
    """This process's live children, but multiprocessing's resource tracker (one per process, for its lifetime)."""
    alive = set()
    for child in psutil.Process().children(recursive=True):
        with contextlib.suppress(psutil.NoSuchProcess):  # a zombie included: it ended
            if "resource_tracker" not in " ".join(child.cmdline()):
                alive.add(child.pid)
    return alive


async def none_left_but(before: set[int]) -> None:
    """Wait for what the failed start spawned to end (a process still spawning is killed once it exists)."""
    await wait_until(lambda: not children() - before, 10, "the failed start's processes to end")


async def test_a_vehicle_that_cannot_connect_stops_the_start_and_the_loading_processor(tmp_path: Path) -> None:
    before = children()
    core = UavCore(config(tmp_path, fc="serial:///dev/no-such-uart:57600"))
    with pytest.raises(ConnectError, match="no-such-uart"):
        await core.start()
    await none_left_but(before)


async def test_a_processor_that_cannot_load_stops_the_start_and_the_simulator(tmp_path: Path) -> None:
    before = children()
    core = UavCore(with_overrides(config(tmp_path), processor=f"{tmp_path / 'slow.py'}:NoSuchClass", fc="sim"))
    with pytest.raises(ProcessorLoadError, match="NoSuchClass"):
        await core.start()
    await none_left_but(before)


async def test_an_envelope_that_cannot_be_used_stops_the_start_and_releases_both(tmp_path: Path) -> None:
    """Both came up: the parts are wired then, and a polygon without home stops the start there."""
    before = children()
    away = polygon_file(tmp_path / "away.geojson", [(50, 50), (50, 80), (80, 80), (80, 50)])
    core = UavCore(config(tmp_path, fc="sim", polygon=str(away)))
    with pytest.raises(ConfigError, match="outside the polygon"):
        await core.start()
    await none_left_but(before)
