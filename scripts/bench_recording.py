"""Recording cost: processed FPS with every frame saved (640x480 JPEG) vs recording off.

The template processor saves every frame itself (``save_every=1``: ``tmMgr.save`` with its brightness),
so each frame costs a copy on the processor thread and a JPEG encode + write on the writer thread.
Two cameras: a real-time 30 FPS one (what a drone has; the goal is a ratio >= 0.95) and an unpaced one
(frames as fast as they can be rendered: the worst case, where recording competes for the CPU).
Prints one JSON object.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from uav_tui.config import load_config  # noqa: E402
from uav_tui.core import UavCore  # noqa: E402


async def measure(source: str, record: bool, seconds: float, runs_dir: str) -> dict[str, float]:
    overrides = {"source": source, "processor": "template", "processor_args": {"save_every": 1}, "fc": "none",
                 "record": record, "runs_dir": runs_dir, "min_free_mb": 0.0}
    core = UavCore(load_config(None, overrides))
    await core.start()
    await asyncio.sleep(1.0)  # warm-up
    frames0, wall0, cpu0 = core.worker.stats.frames_processed, time.perf_counter(), time.process_time()
    saved0 = core.recorder.writer.images_written if core.recorder else 0
    await asyncio.sleep(seconds)
    frames = core.worker.stats.frames_processed - frames0
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    recording = core.status().recording
    saved = (core.recorder.writer.images_written - saved0) if core.recorder else 0
    await core.stop()
    result = {"processed_fps": frames / wall, "cpu_ms_per_frame": 1000 * cpu / max(1, frames)}
    if record:
        result.update(saved_fps=saved / wall, dropped=recording["dropped"],
                      mb_per_s=recording["bytes"] / max(1, recording["frames"]) * frames / wall / 1e6)
    return result


async def main() -> dict[str, object]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=6.0, help="measured time per run")
    args = parser.parse_args()
    report: dict[str, object] = {"frame": "640x480 BGR -> JPEG q90", "processor": "template, save_every=1"}
    with tempfile.TemporaryDirectory() as runs_dir:
        for name, source in (("camera_30fps", "synthetic:?fps=30"), ("unpaced", "synthetic:?realtime=0")):
            off = await measure(source, False, args.seconds, runs_dir)
            on = await measure(source, True, args.seconds, runs_dir)
            report[name] = {"off": off, "every_frame": on, "ratio": on["processed_fps"] / off["processed_fps"]}
    report["goal_ratio"] = 0.95
    report["ratio"] = report["camera_30fps"]["ratio"]  # type: ignore[index]
    return report


def _rounded(value: object) -> object:
    if isinstance(value, dict):
        return {k: _rounded(v) for k, v in value.items()}
    return round(value, 3) if isinstance(value, float) else value


if __name__ == "__main__":
    logging.basicConfig(level=logging.ERROR)
    print(json.dumps(_rounded(asyncio.run(main())), indent=2))
