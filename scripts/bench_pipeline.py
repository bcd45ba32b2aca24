"""Platform overhead: the uav-tui pipeline vs the paper's bare loop, on the same video file.

Bare loop: ``ok, frame = cap.read(); alg.photo_processing(frame)`` as fast as it goes.
Platform: ``file:VIDEO?realtime=0`` through the capture thread, FrameBuffer and processor worker.
Also a real-time (30 FPS) run for the frame age and the capture-to-processed latency a camera sees.
Prints one JSON object.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from processors import load_processor  # noqa: E402
from sources.synthetic import SyntheticScene  # noqa: E402
from uav_tui.config import load_config  # noqa: E402
from uav_tui.core import UavCore  # noqa: E402
from uav_tui.worker import ProcessedFrame  # noqa: E402


def make_video(path: Path, frames: int, width: int = 640, height: int = 480) -> None:
    scene = SyntheticScene(width, height, seed=1)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 30, (width, height))
    for i in range(frames):
        writer.write(scene.render(i))
    writer.release()


def bare_loop(path: Path, processor: str, seconds: float) -> dict[str, float]:
    algorithm = load_processor(processor).instance
    cap = cv2.VideoCapture(str(path), cv2.CAP_FFMPEG)
    frames, wall0, cpu0 = 0, time.perf_counter(), time.process_time()
    while time.perf_counter() - wall0 < seconds:
        ok, frame = cap.read()
        if not ok:
            cap.set(cv2.CAP_PROP_POS_FRAMES, 0)
            continue
        algorithm.photo_processing(frame)
        frames += 1
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    cap.release()
    return {"fps": frames / wall, "cpu_s_per_frame": cpu / frames, "frames": frames}


async def platform_run(source: str, processor: str, seconds: float) -> dict[str, float]:
    core = UavCore(load_config(None, {"source": source, "processor": processor, "fc": "none", "record": False}))
    results: list[tuple[int, int, int, int]] = []  # (seq, captured, started, ready): never keep the images

    def record(r: ProcessedFrame) -> None:
        results.append((r.frame.seq, r.frame.t_mono_ns, r.t_start_ns, r.t_vector_ns or r.t_end_ns))

    await core.start()
    core.add_frame_listener(record)
    await asyncio.sleep(1.0)  # warm-up: decoder and caches
    results.clear()
    wall0, cpu0 = time.perf_counter(), time.process_time()
    await asyncio.sleep(seconds)
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    snapshot = list(results)
    await core.stop()
    stamps = np.array(snapshot, dtype=np.int64).reshape(-1, 4)
    age = (stamps[:, 2] - stamps[:, 1]) / 1e6
    latency = (stamps[:, 3] - stamps[:, 1]) / 1e6
    seqs = stamps[:, 0].tolist()
    return {
        "fps": len(snapshot) / wall,
        "cpu_s_per_frame": cpu / max(1, len(snapshot)),
        "frames": len(snapshot),
        "skipped": (seqs[-1] - seqs[0] + 1 - len(seqs)) if seqs else 0,
        "frame_age_ms_p50": float(np.percentile(age, 50)),
        "frame_age_ms_p95": float(np.percentile(age, 95)),
        "latency_ms_p50": float(np.percentile(latency, 50)),
        "latency_ms_p95": float(np.percentile(latency, 95)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=8.0)
    parser.add_argument("--processor", default="template")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        video = Path(tmp) / "bench.mp4"
        make_video(video, 300)
        bare = bare_loop(video, args.processor, args.seconds)
        fast = asyncio.run(platform_run(f"file:{video}?realtime=0", args.processor, args.seconds))
        paced = asyncio.run(platform_run(f"file:{video}", args.processor, args.seconds))
    print(json.dumps({
        "processor": args.processor,
        "resolution": "640x480",
        "bare_loop": bare,
        "platform_as_fast_as_possible": fast,
        "platform_30fps_camera": paced,
        "fps_ratio_platform_vs_bare": fast["fps"] / bare["fps"],
        "cpu_ratio_platform_vs_bare": fast["cpu_s_per_frame"] / bare["cpu_s_per_frame"],
        "goal_fps_ratio": 0.95,
    }, indent=2))


if __name__ == "__main__":
    main()
