"""The README's quick start with ``csrt``: the demo car followed for two minutes (:mod:`.quickstart_follow`)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.processors.quickstart_follow import TIMEOUT_S, follow_the_demo_car


@pytest.mark.timeout(TIMEOUT_S)
async def test_the_quick_start_csrt_follows_the_demo_car_for_two_minutes(tmp_path: Path) -> None:
    await follow_the_demo_car(tmp_path, "csrt", by_iou=False)
