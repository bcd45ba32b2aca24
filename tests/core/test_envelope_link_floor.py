"""The link-quality floor on the built-in vehicle: its RC signal fades (the truth channel sets RC_CHANNELS' rssi)."""

from __future__ import annotations

import asyncio
import re
from pathlib import Path

from tests.core.flight_helpers import flying_core, wait_until


async def test_a_link_below_its_floor_for_link_floor_s_returns_home_and_an_unknown_one_never_acts(
        tmp_path: Path) -> None:
    async with flying_core(tmp_path, link_floor_pct=50.0, link_floor_s=1.0) as core:
        core.truth.request({"cmd": "link_quality", "pct": 80.0})
        await wait_until(lambda: core.telemetry.snapshot().link_quality_pct is not None, 5, "the link quality")
        assert abs(core.telemetry.snapshot().link_quality_pct - 80.0) < 0.5  # type: ignore[operator]
        await core.execute("f 1")
        await core.execute("autonomy on")
        core.truth.request({"cmd": "link_quality", "pct": None})  # the receiver gone: not known, nothing ends
        await wait_until(lambda: core.telemetry.snapshot().link_quality_pct is None, 5, "the link quality unknown")
        await asyncio.sleep(1.5)
        assert core.gate.enabled, core.gate.stop_reason
        core.truth.request({"cmd": "link_quality", "pct": 30.0})
        took = await wait_until(lambda: not core.gate.enabled, 5, "autonomy to end below the link floor")
        assert 0.9 <= took <= 2.0, f"ended {took:.2f} s after the link fell below its floor"
        assert re.fullmatch(r"link quality 30 % below the floor 50 % for 1 s: RTL", core.gate.stop_reason)
        assert any(e.message == f"autonomy OFF: {core.gate.stop_reason}" for e in core.events.recent)
        await wait_until(lambda: core.truth.latest()["mode"] == "RTL", 5, "the return home")
