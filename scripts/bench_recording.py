"""Recording cost: processed FPS with every frame saved (640x480 JPEG) vs recording off; the video; replay speed.

The template processor saves every frame itself (``save_every=1``: ``tmMgr.save`` with its brightness),
so each frame costs a copy on the processor thread and a JPEG encode + write on the writer thread.
Two cameras: a real-time 30 FPS one (what a drone has; the goal is a ratio >= 0.95) and an unpaced one
(frames as fast as they can be rendered: the worst case, where recording competes for the CPU).
``camera_30fps_vehicle``: the 30 FPS camera with the built-in simulator's telemetry, where every frame row waits
on the writer thread for the telemetry after its capture (``writer_cpu_pct``: that thread's CPU).

``video``: recording on with ``record_video`` on vs off (template processor, no JPEGs), 30 FPS at
640x480 and 1280x720: the processed-FPS ratio (goal >= 0.97) and the CPU of the writer thread, where
the encoder runs, and of the capture thread, which copies each frame (goal <= 15 % of one core at
640x480 for the encoder). ``replay``: a recorded 640x480 run replayed with ``--speed max`` through the
template processor, frames per second. Prints one JSON object.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import sys
import tempfile
import threading
import time
from pathlib import Path

import cv2
import psutil

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from sources.synthetic import SyntheticScene  # noqa: E402
from uav_tui.config import load_config  # noqa: E402
from uav_tui.core import UavCore  # noqa: E402
from uav_tui.recording.video import ENCODERS, VIDEO_FILE, VideoFrame, VideoStage, describe_video  # noqa: E402
from uav_tui.recording.writer import DiskWriter  # noqa: E402
from uav_tui.replay.runner import ReplayJob, replay  # noqa: E402


async def measure(source: str, record: bool, seconds: float, runs_dir: str, fc: str = "none") -> dict[str, float]:
    overrides = {"source": source, "processor": "template", "processor_args": {"save_every": 1}, "fc": fc,
                 "record": record, "record_video": False, "runs_dir": runs_dir, "min_free_mb": 0.0}
    core = UavCore(load_config(None, overrides))
    await core.start()
    await asyncio.sleep(1.0)  # warm-up
    frames0, wall0, cpu0 = core.worker.stats.frames_processed, time.perf_counter(), time.process_time()
    writer0 = _thread_cpu_s("recorder-writer")
    saved0 = core.recorder.writer.images_written if core.recorder else 0
    await asyncio.sleep(seconds)
    frames = core.worker.stats.frames_processed - frames0
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    writer = _thread_cpu_s("recorder-writer") - writer0
    recording = core.status().recording
    saved = (core.recorder.writer.images_written - saved0) if core.recorder else 0
    await core.stop()
    result = {"processed_fps": frames / wall, "cpu_ms_per_frame": 1000 * cpu / max(1, frames)}
    if record:
        result.update(saved_fps=saved / wall, dropped=recording["dropped"], writer_cpu_pct=100 * writer / wall,
                      mb_per_s=recording["bytes"] / max(1, recording["frames"]) * frames / wall / 1e6)
    return result


def _thread_cpu_s(*prefixes: str) -> float:
    """CPU seconds (user + system) of this process's threads whose names start with one of ``prefixes``."""
    ids = {thread.native_id for thread in threading.enumerate() if thread.name.startswith(prefixes)}
    return sum(t.user_time + t.system_time for t in psutil.Process().threads() if t.id in ids)


async def measure_video(width: int, height: int, video: bool, seconds: float, runs_dir: str) -> dict[str, float]:
    overrides = {"source": f"synthetic:?fps=30&width={width}&height={height}", "processor": "template", "fc": "none",
                 "record": True, "record_video": video, "runs_dir": runs_dir, "min_free_mb": 0.0}
    core = UavCore(load_config(None, overrides))
    await core.start()
    await asyncio.sleep(1.0)  # warm-up (the encoder opens on the first frame)
    frames0, wall0 = core.worker.stats.frames_processed, time.perf_counter()
    writer0, capture0 = _thread_cpu_s("recorder-writer"), _thread_cpu_s("capture-")
    assert core.recorder is not None
    video_file = core.recorder.run_dir / VIDEO_FILE
    video0 = video_file.stat().st_size if video else 0
    await asyncio.sleep(seconds)
    wall = time.perf_counter() - wall0
    frames = core.worker.stats.frames_processed - frames0
    video_mb = (video_file.stat().st_size - video0) / 1e6 if video else 0.0
    writer, capture = _thread_cpu_s("recorder-writer") - writer0, _thread_cpu_s("capture-") - capture0
    recording = core.status().recording
    await core.stop()
    return {"processed_fps": frames / wall, "writer_cpu_pct": 100 * writer / wall,
            "capture_cpu_pct": 100 * capture / wall, "dropped": recording["dropped"],
            "video_mb_per_min": video_mb * 60 / wall}


def measure_encoders(width: int, height: int, count: int = 90) -> dict[str, float]:
    """CPU ms per frame of each way to write the video: PyAV (H.264, MJPEG) as the recorder does, OpenCV's writer."""
    frames = [SyntheticScene(width, height).render(i) for i in range(count)]
    result = {}
    with tempfile.TemporaryDirectory() as folder:
        for encoder in ENCODERS:
            stage = VideoStage(DiskWriter(Path(folder), {}), encoder)  # the recorder's encoder, run on this thread
            start = time.process_time()
            for i, image in enumerate(frames):
                stage.handle(VideoFrame(image, i + 1, i * 33_333_333, 0))
            stage.drain()
            result[f"pyav_{encoder[0]}_mpegts"] = 1000 * (time.process_time() - start) / count
        writer = cv2.VideoWriter(str(Path(folder) / "opencv.avi"), cv2.VideoWriter_fourcc(*"MJPG"), 30, (width, height))
        start = time.process_time()
        for image in frames:
            writer.write(image)
        writer.release()
        result["opencv_mjpg_avi"] = 1000 * (time.process_time() - start) / count
    return result


async def measure_replay(seconds: float, runs_dir: str) -> dict[str, float]:
    """Record ``seconds`` of a 640x480 30 FPS camera, then replay it at --speed max through the template processor."""
    overrides = {"source": "synthetic:?fps=30", "processor": "template", "fc": "none", "runs_dir": runs_dir,
                 "min_free_mb": 0.0}
    core = UavCore(load_config(None, overrides))
    await core.start()
    await asyncio.sleep(seconds)
    await core.stop()
    assert core.recorder is not None
    result = await replay(ReplayJob(str(core.recorder.run_dir), load_config(None, overrides), "max"))
    return {"frames": result.frames, "seconds": result.seconds, "frames_per_s": result.frames / result.seconds}


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
        # With a vehicle (the built-in simulator's telemetry): frame rows wait on the writer thread for the sample
        # after their capture, and are interpolated there.
        off = await measure("synthetic:?fps=30", False, args.seconds, runs_dir, fc="sim")
        on = await measure("synthetic:?fps=30", True, args.seconds, runs_dir, fc="sim")
        report["camera_30fps_vehicle"] = {"off": off, "every_frame": on,
                                          "ratio": on["processed_fps"] / off["processed_fps"]}
        report["goal_ratio"] = 0.95
        report["ratio"] = report["camera_30fps"]["ratio"]  # type: ignore[index]
        video: dict[str, object] = {"codec": describe_video(), "goal_ratio": 0.97, "goal_encoder_cpu_pct_640x480": 15,
                                    "encoder_cpu_ms_per_frame_640x480": measure_encoders(640, 480)}
        for width, height in ((640, 480), (1280, 720)):
            off = await measure_video(width, height, False, args.seconds, runs_dir)
            on = await measure_video(width, height, True, args.seconds, runs_dir)
            video[f"{width}x{height}"] = {
                "off": off, "on": on, "ratio": on["processed_fps"] / off["processed_fps"],
                "encoder_cpu_pct": on["writer_cpu_pct"] - off["writer_cpu_pct"],
                "capture_copy_cpu_pct": on["capture_cpu_pct"] - off["capture_cpu_pct"]}
        report["video"] = video
        report["replay_max_speed"] = await measure_replay(args.seconds, runs_dir)
    return report


def _rounded(value: object) -> object:
    if isinstance(value, dict):
        return {k: _rounded(v) for k, v in value.items()}
    return round(value, 3) if isinstance(value, float) else value


if __name__ == "__main__":
    logging.basicConfig(level=logging.ERROR)
    print(json.dumps(_rounded(asyncio.run(main())), indent=2))
