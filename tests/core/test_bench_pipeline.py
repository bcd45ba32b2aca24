"""``scripts/bench_pipeline.py`` compares like with like: its bare loop replays exactly the frames the platform
processed, from the frame the target was selected on, and says so only when the tracker did the same on each."""

from __future__ import annotations

import asyncio
import dataclasses
import importlib.util
import sys
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import pytest

from processors.detection import find_data_dir

ROOT = Path(__file__).resolve().parents[2]
AERIAL = find_data_dir() / "aerial-tracking"
SIZE = (320, 240)


@pytest.fixture(scope="module")
def bench() -> Iterator[ModuleType]:
    spec = importlib.util.spec_from_file_location("bench_pipeline", ROOT / "scripts" / "bench_pipeline.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclass looks itself up there
    spec.loader.exec_module(module)
    yield module
    del sys.modules[spec.name]


@pytest.mark.skipif(not AERIAL.is_dir(), reason=f"{AERIAL} is not here")
def test_the_bare_loop_replays_the_frames_the_platform_tracked(bench: ModuleType, tmp_path: Path,
                                                               monkeypatch: pytest.MonkeyPatch) -> None:
    video = tmp_path / "aerial.mp4"
    bench.make_video(video, bench.aerial_frames(*SIZE), *SIZE)
    monkeypatch.setattr(bench, "WARM_UP_S", 1.0)
    roi = bench.target_roi(*SIZE)
    run, replayed = asyncio.run(bench.platform_run(f"file:{video}?realtime=0", "csrt", "process", 1.0, roi))
    assert replayed.selected is not None and replayed.selected < replayed.first
    assert run["frames"] == replayed.last - replayed.first + 1 == len(replayed.boxes)  # lockstep: none skipped
    assert any(replayed.boxes)  # it tracked something

    bare = bench.bare_loop(video, "csrt", replayed, roi, None)
    assert bare["frames"] == run["frames"]
    differs = bare["first_different_frame"]
    assert differs is None, (f"the bare loop tracked something else from frame {differs} on (selected on "
                             f"{replayed.selected}, measured from {replayed.first}); the platform tracked "
                             f"{replayed.boxes[differs - replayed.first:][:3]} there")

    selected_later = dataclasses.replace(replayed, selected=replayed.selected + 5)
    assert bench.bare_loop(video, "csrt", selected_later, roi, None)["first_different_frame"] is not None
