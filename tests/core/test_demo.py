"""The README demo, headless: built-in vehicle and camera, position hold flying vectors, land, exit 0."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.core.demo_flight import fly_demo


@pytest.mark.timeout(300)  # the whole demo flight, in a process that may itself take 120 s
def test_demo_script_flies_and_lands(tmp_path: Path) -> None:
    demo = fly_demo("sim", tmp_path)
    status = demo.status
    assert max(r["telemetry"]["rel_alt_m"] or 0 for r in status) > 9  # took off to 10 m
    assert max(r["vectors_executed"] for r in status) > 3  # the processor's vectors flew the vehicle
    assert status[-1]["telemetry"]["armed"] is False and status[-1]["telemetry"]["rel_alt_m"] < 0.3  # landed
    assert (demo.run.frames.decision == "executed").sum() > 3
    assert demo.run.telemetry.rel_alt_m.max() > 9
