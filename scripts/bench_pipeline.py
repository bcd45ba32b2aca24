"""Platform overhead: the uav-tui pipeline (processor in its own process, or on a thread) vs the paper's bare loop.

Platform: ``file:VIDEO?realtime=0`` (the file source runs in lockstep with its reader) through the capture
thread, FrameBuffer and the processor worker, with ``isolation = "process"`` and ``"thread"``.
Bare loop: ``ok, frame = cap.read(); alg.photo_processing(frame)`` as fast as it goes, each time in a fresh
interpreter as a researcher's script runs: glibc's default allocator and OpenCV's default thread pool (the platform
sets its own for the processor's process, see ``uav_tui.hosting.malloc_tuning`` and ``uav_tui.hosting.opencv_pool``).
After each platform run, the bare loop replays exactly the frames that run processed: from the frame the target
was selected on (csrt; untimed up to the measured frames), then the measured frames, timed. A tracker's work per
frame depends on what it is doing: on real 1280x720 video, CSRT lost its target on 10 % of the first 300 frames
after the selection (7.2-7.6 ms a frame) and on 25 % of the frames the platform measures after its warm-up
(8.1-8.9 ms), so a bare loop timed from the selection did less work a frame than the platform. ``same_work``
says both tracked the same box on every measured frame (else ``first_different_frames`` says where they parted).

For every reference processor (csrt with a target selected) at 640x480 and 1280x720: processed FPS, CPU
per processed frame (with the processor's own process counted), and the hand-off time: from the moment
both a frame and the processor were ready (``max(capture, previous frame done)``) to processing start,
p50/p95 — the cost of getting a frame into the processor, without the time spent waiting for it.
Goals (ratios within one run): FPS >= 0.95x the bare loop, CPU/frame <= 1.1x, hand-off p95 <= 1 ms at
1280x720. Prints one JSON object.

A shared or throttled machine drifts by tens of percent within minutes, so each configuration runs in
``--rounds`` rounds of process, thread and their bare loops back to back; a ratio is taken within its round and
the median over the rounds is reported (with every round's value).

``--footage aerial`` replays real drone video instead of the generated scene: 25 frames of each sequence of the
aerial-tracking set (``$UAV_TUI_DATA_DIR``, else ``shared/data`` beside the repository), resized to each resolution.
Real frames take longer to decode than the scene's flat shapes, so the platform's fixed cost per frame weighs less.

``--camera`` measures the regime a drone flies in instead: frames at the video's 30 FPS (``realtime=1``,
the bare loop paced the same), where every frame finds the processor idle. It reports CPU per frame, the
platform's extra CPU as a share of one core, and capture-to-result latency p50/p95 (no goals).
"""

from __future__ import annotations

import argparse
import asyncio
import itertools
import json
import multiprocessing
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from processors import load_processor  # noqa: E402
from processors.base import read_box  # noqa: E402
from sources.synthetic import SyntheticScene  # noqa: E402
from uav_tui.errors import ConfigError  # noqa: E402
from uav_tui.evaluation import find_sequences  # noqa: E402
from uav_tui.evaluation.sequences import aerial_tracking_set  # noqa: E402
from uav_tui.evaluation.throughput import Replayed, latency_percentiles, platform_run  # noqa: E402
from uav_values.box import PixelBox  # noqa: E402

PROCESSORS = ("template", "csrt", "position_hold", "yolo")
RESOLUTIONS = ((640, 480), (1280, 720))
VIDEO_FPS = 30
GOALS = {"fps_ratio_min": 0.95, "cpu_ratio_max": 1.1, "handoff_p95_ms_max_at_1280x720": 1.0}


FRAMES = 150
AERIAL_FRAMES_PER_SEQUENCE = 25
BARE_WARM_UP_FRAMES = 30
"""Processed untimed before the bare loop's measured frames, when no target was selected."""


def synthetic_frames(width: int, height: int) -> Iterator[np.ndarray]:
    scene = SyntheticScene(width, height, seed=1)
    return (scene.render(i) for i in range(FRAMES))


def aerial_frames(width: int, height: int) -> Iterator[np.ndarray]:
    """The first frames of every aerial-tracking sequence, resized (SequenceError when the set is not there)."""
    for sequence in find_sequences([aerial_tracking_set()]):
        for frame in itertools.islice(sequence.frames(), AERIAL_FRAMES_PER_SEQUENCE):
            yield cv2.resize(frame, (width, height), interpolation=cv2.INTER_AREA)


FOOTAGE = {"synthetic": synthetic_frames, "aerial": aerial_frames}


def make_video(path: Path, frames: Iterable[np.ndarray], width: int, height: int) -> None:
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), VIDEO_FPS, (width, height))
    for frame in frames:
        writer.write(frame)
    writer.release()


def footage_videos(resolutions: str, footage: str, folder: Path) -> Iterator[tuple[tuple[int, int], Path]]:
    """Each size of ``resolutions`` (``"640x480,1280x720"``) and ``footage`` written at it in ``folder``."""
    for text in resolutions.split(","):
        width, height = (int(v) for v in text.split("x"))
        video = folder / f"bench-{text}.mp4"
        make_video(video, FOOTAGE[footage](width, height), width, height)
        yield (width, height), video


def target_roi(width: int, height: int) -> tuple[int, int, int, int]:
    """The region csrt is given: the middle of the frame."""
    return width // 2 - width // 16, height // 2 - height // 16, width // 8, height // 8


def bare_loop(path: Path, processor: str, replayed: Replayed, roi: PixelBox | None,
              fps: float | None) -> dict[str, Any]:
    """The frames ``replayed`` says: untimed from the selection (or :data:`BARE_WARM_UP_FRAMES` frames before the
    measured ones), then the measured ones as fast as it goes, or paced at ``fps`` like a camera (then with
    read-to-result latency)."""
    algorithm = load_processor(processor).instance
    cap = cv2.VideoCapture(str(path), cv2.CAP_FFMPEG)
    start = replayed.selected or max(1, replayed.first - BARE_WARM_UP_FRAMES)
    for _ in range((start - 1) % int(cap.get(cv2.CAP_PROP_FRAME_COUNT))):
        _read_looping(cap)
    if roi is not None:
        algorithm.catch_cmd(roi)
    for _ in range(start, replayed.first):
        algorithm.photo_processing(_read_looping(cap))
    frames = replayed.last - replayed.first + 1
    boxes: list[PixelBox | None] = []
    latencies: list[float] = []
    wall0, cpu0 = time.perf_counter(), time.process_time()
    for index in range(frames):
        if fps:
            time.sleep(max(0.0, wall0 + index / fps - time.perf_counter()))
        frame = _read_looping(cap)
        read = time.perf_counter()
        algorithm.photo_processing(frame)
        latencies.append(time.perf_counter() - read)
        boxes.append(read_box(algorithm))  # as the platform reads it after every frame
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    cap.release()
    return {"fps": frames / wall, "cpu_s_per_frame": cpu / frames, "frames": frames,
            "first_different_frame": _first_difference(boxes, replayed),
            **(latency_percentiles(np.array(latencies) * 1e3) if fps else {})}


def _read_looping(cap: cv2.VideoCapture) -> np.ndarray:
    """The next frame, from the first again after the last (as the file source does)."""
    ok, frame = cap.read()
    if not ok:
        cap.set(cv2.CAP_PROP_POS_FRAMES, 0)
        ok, frame = cap.read()
    return frame


def rounds(processor: str, size: tuple[int, int], video: Path, seconds: float, count: int,
           camera: bool) -> dict[str, Any]:
    """``count`` rounds of process and thread, each with its bare loop; each measure is the median over the
    rounds, with the rounds' values in ``"<name>_rounds"``. ``"bare_loop"`` is the process runs' bare loop."""
    roi = target_roi(*size) if processor == "csrt" else None
    source = f"file:{video}?realtime={int(camera)}"
    measured: dict[str, list[dict[str, float]]] = {"bare_loop": [], "process": [], "thread": []}
    different_from: list[int] = []
    for _ in range(count):
        for isolation in ("process", "thread"):
            run, replayed = asyncio.run(platform_run(source, processor, isolation, seconds, roi))
            bare = in_fresh_interpreter(bare_loop, video, processor, replayed, roi, VIDEO_FPS if camera else None)
            if (differs := bare.pop("first_different_frame")) is not None:
                different_from.append(differs)
            if isolation == "process":
                measured["bare_loop"].append(bare)
            measured[isolation].append({**run, **(extra_cpu(bare, run) if camera else ratios(bare, run))})
    entry: dict[str, Any] = {"processor": processor, "resolution": f"{size[0]}x{size[1]}", "rounds": count}
    for name, runs in measured.items():
        entry[name] = {key: float(np.median([run[key] for run in runs])) for key in runs[0]}
        for key in ("fps", "fps_ratio_vs_bare", "cpu_ratio_vs_bare", "extra_cpu_ms_per_frame"):
            if key in runs[0]:
                entry[name][f"{key}_rounds"] = [round(run[key], 3) for run in runs]
    entry["same_work"] = not different_from
    if different_from:
        entry["first_different_frames"] = different_from
    return entry


def in_fresh_interpreter(function: Callable[..., dict[str, Any]], *args: Any) -> dict[str, Any]:
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as fresh_interpreter:
        return fresh_interpreter.submit(function, *args).result()


def _first_difference(bare: list[PixelBox | None], platform: Replayed) -> int | None:
    """The first frame the platform processed (its sequence number) on which the bare loop, which processed every
    measured frame, did not track what the platform did (the same box within a pixel, or nothing in both); None
    when it did on every one."""
    for seq, p in zip(platform.seqs, platform.boxes, strict=True):
        b = bare[seq - platform.first]
        if not (b is p if b is None or p is None else np.allclose(b, p, atol=1)):
            return seq
    return None


def ratios(bare: dict[str, float], run: dict[str, float]) -> dict[str, float]:
    return {"fps_ratio_vs_bare": run["fps"] / bare["fps"],
            "cpu_ratio_vs_bare": run["cpu_s_per_frame"] / bare["cpu_s_per_frame"]}


def extra_cpu(bare: dict[str, float], run: dict[str, float]) -> dict[str, float]:
    extra_s = run["cpu_s_per_frame"] - bare["cpu_s_per_frame"]
    return {"extra_cpu_ms_per_frame": extra_s * 1e3, "extra_core_share": extra_s * VIDEO_FPS}


def camera_rate(processor: str, size: tuple[int, int], video: Path, seconds: float, count: int) -> dict[str, Any]:
    """At the video's 30 FPS: CPU per frame, the platform's extra CPU as a share of a core, latency."""
    return {**rounds(processor, size, video, seconds, count, camera=True), "fps": VIDEO_FPS}


def compare(processor: str, size: tuple[int, int], video: Path, seconds: float, count: int) -> dict[str, Any]:
    entry = rounds(processor, size, video, seconds, count, camera=False)
    process = entry["process"]
    entry["goals_met"] = {"fps": process["fps_ratio_vs_bare"] >= GOALS["fps_ratio_min"],
                          "cpu": process["cpu_ratio_vs_bare"] <= GOALS["cpu_ratio_max"]}
    if size == (1280, 720):
        entry["goals_met"]["handoff"] = process["handoff_ms_p95"] <= GOALS["handoff_p95_ms_max_at_1280x720"]
    return entry


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=4.0, help="per measurement")
    parser.add_argument("--rounds", type=int, default=3, help="of process and thread, each with its bare loop")
    parser.add_argument("--processors", default=",".join(PROCESSORS))
    parser.add_argument("--resolutions", default=",".join(f"{w}x{h}" for w, h in RESOLUTIONS))
    parser.add_argument("--camera", action="store_true", help=f"frames at {VIDEO_FPS} FPS, as a camera gives them")
    parser.add_argument("--footage", choices=sorted(FOOTAGE), default="synthetic",
                        help="the video replayed: the generated scene, or real drone video (the aerial-tracking set)")
    args = parser.parse_args()
    if args.footage == "aerial":
        try:
            aerial_tracking_set()
        except ConfigError as exc:
            parser.error(str(exc))
    measure = camera_rate if args.camera else compare
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for size, video in footage_videos(args.resolutions, args.footage, Path(tmp)):
            for processor in args.processors.split(","):
                runs.append(measure(processor, size, video, args.seconds, args.rounds))
                print(f"{processor} {size[0]}x{size[1]} done", file=sys.stderr, flush=True)
    if args.camera:
        print(json.dumps({"mode": f"camera, {VIDEO_FPS} FPS", "footage": args.footage, "runs": runs}, indent=2))
    else:
        print(json.dumps({"goals": GOALS, "footage": args.footage, "runs": runs,
                          "all_goals_met": all(all(r["goals_met"].values()) for r in runs)}, indent=2))


if __name__ == "__main__":
    main()
