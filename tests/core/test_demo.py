"""The README demo, headless: built-in vehicle and camera, position hold flying vectors, land, exit 0."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from uav_tui import dataset

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.timeout(300)  # the whole demo flight, in a process that may itself take 120 s
def test_demo_script_flies_and_lands(tmp_path: Path) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "uav_tui", "--no-ui", "--json", "--fc", "sim", "--source", "sim:?targets=1",
         "--processor", "position_hold", "--script", str(ROOT / "examples" / "demo.txt"),
         "--runs-dir", str(tmp_path / "runs")],
        cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    records = [json.loads(line) for line in result.stdout.splitlines() if line.startswith("{")]
    status = [r for r in records if "pipeline" in r]
    assert max(r["telemetry"]["rel_alt_m"] or 0 for r in status) > 9  # took off to 10 m
    assert max(r["vectors_executed"] for r in status) > 3  # the processor's vectors flew the vehicle
    assert status[-1]["telemetry"]["armed"] is False and status[-1]["telemetry"]["rel_alt_m"] < 0.3  # landed
    run = dataset.load(next((tmp_path / "runs").iterdir()))
    assert (run.frames.decision == "executed").sum() > 3
    assert run.telemetry.rel_alt_m.max() > 9
