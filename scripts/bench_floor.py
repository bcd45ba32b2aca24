"""The floor of process isolation in Python: the least a frame can cost when a processor has a process of its own.

``bench_pipeline.py`` compares the platform with the paper's bare loop (``cap.read(); photo_processing(frame)``);
this measures, on the same footage and against the same bare loop, a hand-off with nothing around it: the
capture decodes each frame into one of two shared-memory slots, publishes its number and wakes the processor's
process with an eventfd; that process touches the frame and answers through another eventfd, while the next
frame is decoded. No event loop, no mailbox lock, no pickled result, no telemetry, no bookkeeping: what is left
is the decoding and one wake-up each way a frame. The processor does nothing, like position hold before F1.

A floor at or under the goals (FPS >= 0.95x, CPU a frame <= 1.1x) says they can be met with a processor in a
process of its own; the platform's distance from the floor is what its per-frame work costs. Each round runs the
bare loop, then the floor on one decoder thread and on FFmpeg's threads (the platform's file source chooses one
of the two), back to back; ratios are taken within a round. Prints one JSON object.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import struct
import sys
import tempfile
import time
from multiprocessing.shared_memory import SharedMemory
from pathlib import Path
from typing import Any

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_pipeline import FOOTAGE, cpu_s, footage_videos  # noqa: E402

SLOTS = 2
GEN = struct.Struct("=q")
"""The number of the frame published (a negative one: stop)."""


def _next_frame(cap: cv2.VideoCapture, into: np.ndarray | None = None) -> np.ndarray:
    ok, frame = cap.read(into)
    if not ok:  # from the first frame again, as the platform's replay does
        cap.set(cv2.CAP_PROP_POS_FRAMES, 0)
        ok, frame = cap.read(into)
    return frame


def bare_loop(video: Path, frames: int) -> tuple[float, float]:
    """FPS and CPU seconds a frame of ``cap.read()`` (OpenCV's default threads) and a processor doing nothing."""
    cap = cv2.VideoCapture(str(video), cv2.CAP_FFMPEG)
    for _ in range(60):
        _next_frame(cap)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    for _ in range(frames):
        _next_frame(cap)[0, 0, 0]
    return frames / (time.perf_counter() - wall0), (time.process_time() - cpu0) / frames


def _processor(slot_names: list[str], shape: tuple[int, ...], control: str, wake: int, done: int) -> None:
    """The processor's process: wait for a frame, touch it, answer."""
    mapped = [SharedMemory(name) for name in [*slot_names, control]]
    slots = [np.ndarray(shape, np.uint8, buffer=shm.buf) for shm in mapped[:-1]]
    while True:
        os.eventfd_read(wake)
        gen = GEN.unpack_from(mapped[-1].buf)[0]
        if gen < 0:
            break
        slots[gen % SLOTS][0, 0, 0]
        os.eventfd_write(done, 1)
    del slots
    for shm in mapped:
        shm.close()


def isolated(video: Path, frames: int, threads: int) -> tuple[float, float]:
    """FPS and CPU seconds a frame (both processes) of the minimal hand-off, decoding on ``threads``."""
    cap = cv2.VideoCapture(str(video), cv2.CAP_FFMPEG, [cv2.CAP_PROP_N_THREADS, threads])
    shape = _next_frame(cap).shape
    shared = [SharedMemory(create=True, size=int(np.prod(shape))) for _ in range(SLOTS)]
    control = SharedMemory(create=True, size=GEN.size)
    slots = [np.ndarray(shape, np.uint8, buffer=shm.buf) for shm in shared]
    wake, done = os.eventfd(0), os.eventfd(0)
    child = multiprocessing.get_context("fork").Process(
        target=_processor, args=([shm.name for shm in shared], shape, control.name, wake, done))
    child.start()
    try:
        for _ in range(60):
            _next_frame(cap)
        wall0, cpu0, child0 = time.perf_counter(), time.process_time(), cpu_s(child.pid)
        for gen in range(1, frames + 1):
            _next_frame(cap, slots[gen % SLOTS])  # while the processor still has the previous frame
            if gen > 1:
                os.eventfd_read(done)
            GEN.pack_into(control.buf, 0, gen)
            os.eventfd_write(wake, 1)
        os.eventfd_read(done)
        wall = time.perf_counter() - wall0
        cpu = time.process_time() - cpu0 + cpu_s(child.pid) - child0
    finally:
        GEN.pack_into(control.buf, 0, -1)
        os.eventfd_write(wake, 1)
        child.join()
        del slots
        for shm in [*shared, control]:
            shm.close()
            shm.unlink()
        os.close(wake)
        os.close(done)
    return frames / wall, cpu / frames


def rounds(video: Path, frames: int, count: int) -> dict[str, Any]:
    runs: dict[str, list[dict[str, float]]] = {"bare_loop": [], "floor_one_thread": [], "floor_ffmpeg_threads": []}
    for _ in range(count):
        bare_fps, bare_cpu = bare_loop(video, frames)
        runs["bare_loop"].append({"fps": bare_fps, "cpu_ms_per_frame": bare_cpu * 1e3})
        for name, threads in (("floor_one_thread", 1), ("floor_ffmpeg_threads", 0)):
            fps, cpu = isolated(video, frames, threads)
            runs[name].append({"fps": fps, "cpu_ms_per_frame": cpu * 1e3, "fps_ratio_vs_bare": fps / bare_fps,
                               "cpu_ratio_vs_bare": cpu / bare_cpu})
    entry: dict[str, Any] = {}
    for name, measured in runs.items():
        entry[name] = {key: round(float(np.median([m[key] for m in measured])), 3) for key in measured[0]}
        for key in ("fps_ratio_vs_bare", "cpu_ratio_vs_bare"):
            if key in measured[0]:
                entry[name][f"{key}_rounds"] = [round(m[key], 3) for m in measured]
    return entry


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=3000, help="per measurement")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--resolutions", default="640x480,1280x720")
    parser.add_argument("--footage", choices=sorted(FOOTAGE), default="aerial")
    args = parser.parse_args()
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for (width, height), video in footage_videos(args.resolutions, args.footage, Path(tmp)):
            runs.append({"resolution": f"{width}x{height}", "frames": args.frames,
                         **rounds(video, args.frames, args.rounds)})
    print(json.dumps({"footage": args.footage, "runs": runs}, indent=2))


if __name__ == "__main__":
    main()
