"""Each reference processor runs under the platform (headless CLI, file source) and yields vectors."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from processors.synthetic import detection_sequence, ground_texture, ground_view, tracking_sequence

REPO = Path(__file__).resolve().parents[2]

"""What libstdc++ / glibc print when the interpreter exits while a daemon thread is inside OpenCV."""


def _write_video(path: Path, frames: list[np.ndarray]) -> Path:
    h, w = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 20, (w, h))
    for frame in frames:
        writer.write(frame)
    writer.release()
    return path


def _frames(kind: str) -> list[np.ndarray]:
    if kind in ("csrt", "nanotrack"):
        return tracking_sequence((320, 240), 40).frames
    if kind == "yolo":
        return detection_sequence((320, 240), 40)[0]
    ground = ground_texture(512)
    return [ground_view(ground, (256.0 + i, 256.0 - i / 2), i / 10, size=(320, 240)) for i in range(40)]


@pytest.mark.parametrize(
    ("processor", "script", "args"),
    [
        ("csrt", "wait 0.2\nroi 138 123 44 52\nwait 3\n", []),
        ("nanotrack", "wait 0.2\nroi 138 123 44 52\nwait 3\n", []),
        ("position_hold", "wait 0.2\nf 1\nwait 3\n", []),
        ("yolo", "wait 3\n", ["--processor-arg", 'follow="person"']),
    ],
    ids=["csrt", "nanotrack", "position_hold", "yolo"],
)
def test_runs_under_platform_with_file_source(processor: str, script: str, args: list[str], tmp_path: Path) -> None:
    video = _write_video(tmp_path / "in.avi", _frames(processor))
    (tmp_path / "script.txt").write_text(script)
    cmd = [
        sys.executable,
        "-m",
        "uav_tui",
        "--no-ui",
        "--json",
        "--no-record",
        "--source",
        f"file:{video}",
        "--processor",
        processor,
        "--script",
        str(tmp_path / "script.txt"),
        *args,
    ]
    env = {**os.environ, "PYTHONPATH": str(REPO)}  # the script's end ends the run: 3 s of frames after the load
    done = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=60)
    lines = [line for line in done.stdout.splitlines() if line.startswith('{"t":')]
    assert lines, done.stderr[-2000:]
    status = json.loads(lines[-1])
    assert status["processor_error"] is None and status["pipeline"]["errors"] == 0
    assert status["pipeline"]["frames_processed"] >= 10
    vx, vy, t = status["last_vector"]
    assert abs(vx) <= 1 and abs(vy) <= 1 and 0 < t <= 2
    assert done.returncode == 0, done.stderr[-2000:]
