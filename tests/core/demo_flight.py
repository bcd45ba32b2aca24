"""Flying the README demo (examples/demo.txt) headless against any MAVLink vehicle, as a user would."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from uav_tui.recorded import dataset

ROOT = Path(__file__).resolve().parents[2]
DEMO = ROOT / "examples" / "demo.txt"


@dataclass
class DemoRun:
    result: subprocess.CompletedProcess[str]
    status: list[dict[str, Any]]
    """The --json status records, in order."""
    run: dataset.Dataset

    def command_t_mono_ns(self, command: str) -> int:
        """When the script's ``command`` was executed (events.csv, monotonic clock)."""
        events = self.run.events
        rows = events[(events.kind == "command") & (events.message == command)]
        assert len(rows), f"no {command!r} in the run's events: {list(events.message)}"
        return int(rows.t_mono_ns.iloc[0])


def fly_demo(fc: str, tmp_path: Path, *, wait_first_s: float = 0.0, timeout_s: float = 180.0) -> DemoRun:
    """``uav-tui --no-ui --fc FC --source sim:?targets=1 --processor position_hold --script demo.txt``.

    ``wait_first_s``: a ``wait`` before the demo, for autopilots that cannot arm right after boot.
    """
    script = tmp_path / "demo.txt"
    script.write_text((f"wait {wait_first_s:g}\n" if wait_first_s else "") + DEMO.read_text())
    result = subprocess.run(
        [sys.executable, "-m", "uav_tui", "--no-ui", "--json", "--fc", fc, "--source", "sim:?targets=1",
         "--processor", "position_hold", "--script", str(script), "--runs-dir", str(tmp_path / "runs")],
        cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True, timeout=timeout_s)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    records = [json.loads(line) for line in result.stdout.splitlines()]
    status = [r for r in records if "pipeline" in r]
    return DemoRun(result, status, dataset.load(next((tmp_path / "runs").iterdir())))
