"""``sim:`` — a camera rendered from the connected vehicle's pose, whatever the autopilot.

The platform passes ``pose_provider`` (:class:`sources.pose.PoseProvider`): the vehicle's pose at a
given capture time, from its telemetry (the built-in simulator, PX4 or ArduPilot SITL alike).
Closing the loop through vision: the processor's vectors move the vehicle, which moves the image.
This module knows nothing about the vehicle beyond that callable.
"""

from __future__ import annotations

import logging
import time
from typing import Any

import numpy as np

from sources.base import CaptureSource
from sources.errors import SourceUriError
from sources.ground import default_ground
from sources.pacing import Pacer
from sources.pose import PoseAt, PoseProvider
from sources.sim_geometry import PinholeCamera, Pose
from sources.sim_marker import GroundMarker, parse_marker
from sources.sim_render import SimRenderer, default_targets
from sources.uri import SourceUri
from uav_values.camera import GIMBAL, MOUNTS, CameraModel, Mount

logger = logging.getLogger(__name__)

MOUNT_TILT_DEG = {**MOUNTS, GIMBAL: 0.0}
"""Camera tilt below the vehicle's nose (on the gimbal: below the gimbal's forward axis) for each named mount;
``tilt=`` overrides it."""

UNKNOWN_GIMBAL = (0.0, -45.0, 0.0)
"""The gimbal's attitude drawn before any gimbal telemetry came (roll, pitch, yaw from the nose): 45 degrees down
ahead, where the built-in simulator's gimbal looks at boot."""


class SimCameraSource(CaptureSource):
    """A pinhole camera over a textured ground, at the pose ``pose_provider`` reports.

    URI: ``sim:[?width=640&height=480&fps=30&hfov=62&mount=down|forward|gimbal&tilt=DEG&targets=N
    &target_speed=1.0&noise=2&seed=0&marker=ID&marker_dict=4x4_50&marker_size=0.5&marker_at=N,E]``; ``marker``
    lays a landing pad (:class:`sources.sim_marker.GroundMarker`) on the ground; ``mount=gimbal`` puts the camera on
    the vehicle's gimbal: it looks with the gimbal's attitude from the pose provider (45 degrees down ahead until
    the first gimbal sample). Without a pose (no provider,
    or no telemetry yet) it renders a hover at 10 m over the origin, so the pipeline always has frames. Its
    properties report, at the newest frame, the pose it was drawn from, each target's ``n``, ``e`` and ground
    ``corners``, and the marker.
    """

    kind = "sim"

    def __init__(self, uri: str = "sim:", *, camera: PinholeCamera | None = None, fps: float = 30.0,
                 targets: int = 0, target_speed: float = 1.0, noise: float = 2.0, seed: int = 0,
                 pose_provider: PoseProvider | None = None, marker: GroundMarker | None = None,
                 on_gimbal: bool = False) -> None:
        self.camera = camera or PinholeCamera()
        self.on_gimbal = on_gimbal
        """The camera rides the vehicle's gimbal (``mount=gimbal``)."""
        self.marker = marker
        super().__init__(uri, f"pinhole {self.camera.hfov_deg:g} deg, tilt {self.camera.tilt_deg:g} deg")
        self.width, self.height, self.fps = self.camera.width, self.camera.height, fps
        self.targets = default_targets(targets, target_speed)
        self.noise, self.seed = noise, seed
        self.pose_provider = pose_provider
        self.pose = Pose()
        self.pose_from_vehicle = False
        self.pose_extrapolated_s = 0.0
        """How far past the newest telemetry sample the last frame's pose was extrapolated."""
        self.renderer: SimRenderer | None = None
        self._pacer: Pacer | None = None
        self._t0 = 0.0
        self._t = 0.0
        self._index = 0
        self._captured_mono_ns = 0

    @classmethod
    def from_uri(cls, uri: SourceUri, *, pose_provider: PoseProvider | None = None,
                 **_context: Any) -> SimCameraSource:
        mount = uri.take_str("mount", "down") or "down"
        if mount not in MOUNT_TILT_DEG:
            raise SourceUriError(f"camera URI {uri.text!r}: mount={mount!r} must be down, forward or gimbal",
                                 key="source")
        hfov = uri.take_float("hfov", 62.0) or 62.0
        if not 1 <= hfov <= 170:
            raise SourceUriError(f"camera URI {uri.text!r}: hfov={hfov:g} must be 1..170 degrees", key="source")
        camera = PinholeCamera(uri.take_int("width", 640) or 640, uri.take_int("height", 480) or 480, hfov,
                               uri.take_float("tilt", MOUNT_TILT_DEG[mount]) or 0.0)
        source = cls(uri.text, camera=camera, fps=uri.take_float("fps", 30.0) or 30.0,
                     targets=uri.take_int("targets", 0) or 0, target_speed=uri.take_float("target_speed", 1.0) or 0.0,
                     noise=uri.take_float("noise", 2.0) or 0.0, seed=uri.take_int("seed", 0) or 0,
                     pose_provider=pose_provider, marker=_marker(uri), on_gimbal=mount == GIMBAL)
        uri.finish()
        return source

    @staticmethod
    def warm_up(uri: SourceUri) -> None:
        """Build the ground texture now (a second or more), e.g. while the simulated vehicle starts."""
        default_ground(uri.take_int("seed", 0) or 0)

    def camera_model(self) -> CameraModel:
        """The renderer's exact model: an ideal pinhole (no distortion) at the vehicle's centre, tilted as rendered."""
        cam = self.camera
        k = cam.intrinsics
        return CameraModel(cam.width, cam.height, float(k[0, 0]), float(k[1, 1]), float(k[0, 2]), float(k[1, 2]), (),
                           Mount(cam.tilt_deg, gimbal=self.on_gimbal), "sim: renderer (exact)")

    def _open_device(self) -> None:
        self._pacer = Pacer(self.fps, self._stop)
        self._t0 = time.monotonic()

    def _grab(self) -> np.ndarray | None:
        assert self._pacer is not None
        if self.renderer is None:  # built here, on the capture thread: the first ground texture takes ~1.5 s
            self.renderer = SimRenderer(self.camera, default_ground(self.seed), self.targets, self.noise, self.seed,
                                        self.marker)
        if not self._pacer.wait():
            return None
        self._captured_mono_ns = time.monotonic_ns()  # the instant this frame shows
        self.pose, self.pose_from_vehicle = self._pose_at(self._captured_mono_ns)
        self._t = self._captured_mono_ns / 1e9 - self._t0
        image = self.renderer.render(self.pose, self._t, self._index)
        self._index += 1
        return image

    def _capture_times(self) -> tuple[int | None, int | None]:
        return self._captured_mono_ns, None  # the frame shows the pose at this instant, not at publishing

    def _pose_at(self, t_mono_ns: int) -> tuple[Pose, bool]:
        if self.pose_provider is None:
            return self._looking(Pose(), None), False
        try:
            found: PoseAt | None = self.pose_provider(t_mono_ns)
        except Exception as exc:  # noqa: BLE001 - a broken provider must not stop the camera
            self._fail(f"pose provider failed: {exc}")
            return self.pose, self.pose_from_vehicle
        if found is None:
            return self._looking(Pose(), None), False
        self.pose_extrapolated_s = found.extrapolated_s
        return self._looking(found.pose, found.gimbal), True

    def _looking(self, pose: Pose, gimbal: tuple[float, float, float] | None) -> Pose:
        """The pose the camera is drawn from: the vehicle's, or on the gimbal, its attitude at the vehicle's place."""
        if not self.on_gimbal:
            return pose
        roll, pitch, yaw = gimbal or UNKNOWN_GIMBAL
        return Pose(pose.n, pose.e, pose.d, roll, pitch, pose.yaw + yaw)

    def _extra_properties(self) -> dict[str, Any]:
        p = self.pose
        positions = [{**dict(zip(("n", "e"), target.position(self._t)[:2], strict=True)),
                      "corners": target.corners(self._t).round(2).tolist()} for target in self.targets]
        marker = None if self.marker is None else {
            "dictionary": self.marker.dictionary, "id": self.marker.marker_id, "size_m": self.marker.size_m,
            "n": self.marker.n, "e": self.marker.e}
        return {"hfov": self.camera.hfov_deg, "tilt": self.camera.tilt_deg, "targets": positions, "marker": marker,
                "pose": {"n": p.n, "e": p.e, "d": p.d, "roll": p.roll, "pitch": p.pitch, "yaw": p.yaw},
                "pose_source": "vehicle telemetry" if self.pose_from_vehicle else "default hover at 10 m (no pose yet)",
                "pose_extrapolated_ms": round(self.pose_extrapolated_s * 1000, 1)}


def _marker(uri: SourceUri) -> GroundMarker | None:
    """The ``marker=ID`` pad of a ``sim:`` URI (``marker_dict``, ``marker_size``, ``marker_at``), or None."""
    marker_id = uri.take_int("marker")
    if marker_id is None:
        stray = sorted(name for name in uri.params if name.startswith("marker_"))
        if stray:
            raise SourceUriError(f"camera URI {uri.text!r}: {', '.join(stray)} need marker=ID (the pad's id)",
                                 key="source")
        return None
    dictionary, size = uri.take_str("marker_dict", "4x4_50") or "", uri.take_float("marker_size", 0.5) or 0.0
    at = uri.take_str("marker_at", "0,0") or ""
    try:
        return parse_marker(dictionary, marker_id, size, at)
    except ValueError as exc:
        raise SourceUriError(f"camera URI {uri.text!r}: {exc}", key="source") from None
