"""Measuring the sim: camera's pose against the simulator's truth channel (tests and scripts/bench_sim_pose.py).

The truth datagrams (50 Hz, stamped with the simulator's ``time.monotonic_ns()``, the same clock
as the camera's on one machine) are collected into a :class:`PoseTrack` of their own, so the truth
is read at exactly each frame's capture time.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

import numpy as np

from controllers.sim.truth import TruthClient
from sources.buffer import Frame
from sources.pose import PoseTrack
from sources.sim_camera import SimCameraSource
from sources.sim_geometry import Pose


class TruthHistory:
    """Every truth datagram from ``client``, collected by a thread until :meth:`close`."""

    def __init__(self, client: TruthClient) -> None:
        self.client = client
        self.track = PoseTrack(history=1_000_000)  # the whole flight: errors are computed afterwards
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._collect, name="truth-history", daemon=True)
        self._thread.start()

    def _collect(self) -> None:
        while not self._stop.is_set():
            try:
                s = self.client.wait_latest(0.5)
            except TimeoutError:
                continue
            self.track.add_position(s["t_mono_ns"], s["n"], s["e"], s["d"])
            self.track.add_attitude(s["t_mono_ns"], s["roll"], s["pitch"], s["yaw"])

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2)


@dataclass(frozen=True, slots=True)
class FramePose:
    t_mono_ns: int
    pose: Pose
    from_vehicle: bool
    extrapolated_s: float
    truth_latest: Pose | None
    """What the old truth-channel path would have drawn: the newest datagram at capture."""


class FramePoses:
    """The pose each frame of a sim: camera was drawn at, recorded on its capture thread."""

    def __init__(self, source: SimCameraSource, truth: TruthClient | None = None) -> None:
        self.source, self.truth = source, truth
        self.frames: list[FramePose] = []
        self.recording = False
        source.buffer.add_listener(self._on_frame)

    def _on_frame(self, frame: Frame) -> None:
        # Called right after the frame was put, before the next is drawn: source.pose is this frame's.
        if self.recording:
            latest = self.truth.latest() if self.truth is not None else None
            self.frames.append(FramePose(frame.t_mono_ns, self.source.pose, self.source.pose_from_vehicle,
                                         self.source.pose_extrapolated_s,
                                         Pose.from_mapping(latest) if latest else None))

    def close(self) -> None:
        self.source.buffer.remove_listener(self._on_frame)


def _yaw_error(a: float, b: float) -> float:
    return abs((a - b + 180.0) % 360.0 - 180.0)


def errors(frames: list[FramePose], truth: PoseTrack, use_truth_latest: bool = False) -> dict[str, np.ndarray]:
    """Per-frame position error (m, 3-D), yaw and tilt (roll/pitch) errors (deg) against the truth at capture."""
    position, yaw, tilt = [], [], []
    for frame in frames:
        drawn = frame.truth_latest if use_truth_latest else frame.pose
        at = truth(frame.t_mono_ns)
        if drawn is None or at is None or at.extrapolated_s > 0.05:
            continue
        t = at.pose
        position.append(math.dist((drawn.n, drawn.e, drawn.d), (t.n, t.e, t.d)))
        yaw.append(_yaw_error(drawn.yaw, t.yaw))
        tilt.append(max(abs(drawn.roll - t.roll), abs(drawn.pitch - t.pitch)))
    return {"position_m": np.array(position), "yaw_deg": np.array(yaw), "tilt_deg": np.array(tilt)}


def percentiles(values: np.ndarray, digits: int = 3) -> dict[str, float]:
    """p50 / p95 / max of ``values``."""
    quantiles = (("p50", 50), ("p95", 95), ("max", 100))
    return {name: round(float(np.percentile(values, q)), digits) for name, q in quantiles}
