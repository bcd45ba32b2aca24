"""Rolling pipeline statistics over the last few seconds of processed frames."""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass

import numpy as np

WINDOW_NS = 3_000_000_000
"""Statistics cover the frames processed in the last three seconds."""


@dataclass(frozen=True, slots=True)
class PipelineStats:
    """A snapshot of how the camera -> processor pipeline is doing."""

    capture_fps: float
    processed_fps: float
    frame_age_ms: float
    """Capture to processing start, median."""
    latency_ms_p95: float
    """Capture to vector ready (or processing end), 95th percentile."""
    processing_ms_p50: float
    processing_ms_p95: float
    frames_processed: int
    frames_skipped: int
    """Captured frames the processor never saw (newer ones replaced them)."""
    errors: int
    busy_ms: float
    """How long the current call into the processor has been running; 0 when idle."""


class RollingStats:
    """Fed one record per processed frame (on the loop); ``snapshot`` summarises the window."""

    def __init__(self) -> None:
        self._samples: deque[tuple[int, int, int, int, int]] = deque()  # done_ns, seq, capture, start, end/vector
        self._captures: deque[tuple[int, int]] = deque([(time.monotonic_ns(), 0)])  # (now_ns, frames captured)
        self.frames_processed = 0
        self.frames_skipped = 0
        self.errors = 0
        self._last_seq = 0

    def add(self, seq: int, t_capture_ns: int, t_start_ns: int, t_end_ns: int, t_ready_ns: int) -> None:
        if self._last_seq and seq > self._last_seq + 1:  # a new source restarts at 1: no skips counted
            self.frames_skipped += seq - self._last_seq - 1
        self._last_seq = seq
        self.frames_processed += 1
        self._samples.append((t_ready_ns, t_capture_ns, t_start_ns, t_end_ns, t_ready_ns))
        self._trim(self._samples, t_ready_ns)

    def snapshot(self, frames_captured: int, busy_since_ns: int | None) -> PipelineStats:
        now = time.monotonic_ns()
        if frames_captured < self._captures[-1][1]:  # a new source counts from zero again
            self._captures.clear()
        self._captures.append((now, frames_captured))
        while len(self._captures) > 2 and self._captures[0][0] < now - WINDOW_NS:
            self._captures.popleft()
        self._trim(self._samples, now)
        samples = np.array(self._samples, dtype=np.int64).reshape(-1, 5)
        span_ns = (now - samples[0, 0]) if len(samples) > 1 else 0
        first_t, first_n = self._captures[0]
        capture_fps = (frames_captured - first_n) * 1e9 / (now - first_t) if now > first_t else 0.0
        if len(samples):
            age = (samples[:, 2] - samples[:, 1]) / 1e6
            processing = (samples[:, 3] - samples[:, 2]) / 1e6
            latency = (samples[:, 4] - samples[:, 1]) / 1e6
            p_age, (p50, p95), p_lat = float(np.median(age)), np.percentile(processing, [50, 95]), \
                float(np.percentile(latency, 95))
        else:
            p_age = p50 = p95 = p_lat = 0.0
        return PipelineStats(
            capture_fps=capture_fps,
            processed_fps=(len(samples) - 1) * 1e9 / span_ns if span_ns else 0.0,
            frame_age_ms=p_age,
            latency_ms_p95=p_lat,
            processing_ms_p50=float(p50),
            processing_ms_p95=float(p95),
            frames_processed=self.frames_processed,
            frames_skipped=self.frames_skipped,
            errors=self.errors,
            busy_ms=(now - busy_since_ns) / 1e6 if busy_since_ns else 0.0,
        )

    @staticmethod
    def _trim(window: deque, now_ns: int) -> None:
        while window and window[0][0] < now_ns - WINDOW_NS:
            window.popleft()
