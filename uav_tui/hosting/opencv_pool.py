"""OpenCV's worker threads in the processor's process: a short spin between jobs, not OpenCV's millisecond.

After each parallel job (``cvtColor``, ``resize``, optical flow, a network's layer, ...) OpenCV's thread pool keeps
every worker spinning for 2000 rounds of pause and ``sched_yield`` (the calling thread for up to 10000) in case
another job follows at once: 0.7 ms of a core a job here. In its own process the processor shares the cores with
the platform's capture thread and the video decoder, and that spinning took the CPU they needed: position hold at
640x480 spent 0.25 ms a frame in its idle OpenCV worker (0.13 ms in the bare loop), and CSRT's hand-off from
capture to processing at 1280x720 took 1.1 ms at p95 (0.2 ms without the spin).

With no spin at all, every job wakes its workers from sleep, and a network is a job per layer: YOLO (Darknet
through OpenCV's DNN) at 1280x720 ran at 0.94x the bare loop's FPS (0.87-1.02 over 5 runs; real video 0.97x).
A tenth of the spin bridges the microseconds between one frame's jobs and ends long before the next frame:
YOLO 1.05x (0.92-1.15; real video 1.05x), an idle worker costs what it costs with no spin (0.08 ms a job), and
CSRT's hand-off p95 stays 0.3-0.5 ms. Template matching, a few jobs a frame, pays 1-3 % more CPU a frame.

OpenCV reads the variables once, when it is loaded, so they are given to the processor's process at its start.
A user's own value for any of them wins.
"""

from __future__ import annotations

from collections.abc import Mapping

ENVIRONMENT = {"OPENCV_THREAD_POOL_ACTIVE_WAIT_WORKER": "200", "OPENCV_THREAD_POOL_ACTIVE_WAIT_MAIN": "1000"}
"""Spin rounds for an idle worker and for the thread waiting on its workers: a tenth of OpenCV's."""


def child_environment(environ: Mapping[str, str]) -> dict[str, str]:
    """``environ`` with :data:`ENVIRONMENT` for the variables it does not set itself."""
    return {**ENVIRONMENT, **environ}
