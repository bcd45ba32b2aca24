"""OpenCV's worker threads in the processor's process: asleep between jobs instead of spinning.

After each parallel job (``cvtColor``, ``resize``, optical flow, ...) OpenCV's thread pool keeps every worker
spinning for 2000 rounds of pause and ``sched_yield`` (the calling thread for up to 10000) in case another job
follows at once. In its own process the processor shares the cores with the platform's capture thread and the
video decoder, and that spinning took the CPU they needed: position hold at 640x480 spent 0.25 ms a frame in
its idle OpenCV worker (0.13 ms in the bare loop, 0.05 ms with these settings), and CSRT's hand-off from capture
to processing at 1280x720 took 1.1 ms at p95 (0.2 ms with them). A sleeping worker is woken for its next job:
at 30 FPS CSRT takes as long as before in its default ``fast`` mode (8.4 ms a frame at 1280x720) and 1 % longer in
``paper`` mode (22-23 ms), for 0.6-1.3 ms (paper: 4 ms) less CPU a frame.

OpenCV reads the variables once, when it is loaded, so they are given to the processor's process at its start.
A user's own value for any of them wins.
"""

from __future__ import annotations

from collections.abc import Mapping

ENVIRONMENT = {"OPENCV_THREAD_POOL_ACTIVE_WAIT_WORKER": "0", "OPENCV_THREAD_POOL_ACTIVE_WAIT_MAIN": "0"}
"""Spin rounds for an idle worker and for the thread waiting on its workers: none, they sleep at once."""


def child_environment(environ: Mapping[str, str]) -> dict[str, str]:
    """``environ`` with :data:`ENVIRONMENT` for the variables it does not set itself."""
    return {**ENVIRONMENT, **environ}
