"""Renders what a pinhole camera on the simulated vehicle sees: the ground, a marker, moving targets, sky, noise."""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from sources.ground import GroundTexture
from sources.sim_geometry import (
    PinholeCamera,
    Pose,
    ground_sample_distance,
    ground_to_image,
    ray_down_coefficients,
)
from sources.sim_marker import GroundMarker

SKY_BGR = (235, 206, 175)
HORIZON_MIN_DOWN = 0.01
"""Rays pointing down less than this (beyond ~100 altitudes away) show sky/haze instead of aliasing."""


@dataclass(frozen=True, slots=True)
class GroundTarget:
    """A patterned rectangle driving in a circle on the ground (a car seen from above)."""

    centre_n: float
    centre_e: float
    radius_m: float
    speed_ms: float
    phase: float
    length_m: float = 4.0
    width_m: float = 2.0

    def position(self, t: float) -> tuple[float, float, float]:
        """(n, e, heading rad) at time ``t`` seconds."""
        angle = self.phase + (self.speed_ms * t / self.radius_m if self.radius_m > 0 else 0.0)
        n = self.centre_n + self.radius_m * math.cos(angle)
        e = self.centre_e + self.radius_m * math.sin(angle)
        return n, e, angle + math.pi / 2

    def corners(self, t: float) -> np.ndarray:
        """The four ground corners (n, e), front-left first, clockwise seen from above."""
        n, e, heading = self.position(t)
        fwd = np.array([math.cos(heading), math.sin(heading)]) * self.length_m / 2
        right = np.array([-math.sin(heading), math.cos(heading)]) * self.width_m / 2
        centre = np.array([n, e])
        return np.array([centre + fwd - right, centre + fwd + right, centre - fwd + right, centre - fwd - right])


def default_targets(count: int, speed_ms: float) -> list[GroundTarget]:
    """``count`` targets circling the origin on rings 6 m apart, starting at different angles."""
    return [GroundTarget(0.0, 0.0, 6.0 * (i + 1), speed_ms, phase=2.4 * i) for i in range(count)]


def _target_patch(seed: int) -> np.ndarray:
    """A 64 x 128 px red-and-white roof pattern, front at the top."""
    rng = np.random.default_rng(seed)
    patch = np.full((128, 64, 3), (40, 40, 200), np.uint8)
    patch[16:40, 8:56] = (230, 230, 230)
    patch[88:112, 8:56] = (30, 30, 30)
    patch[::16, :] = (255, 255, 255)
    noise = rng.integers(-25, 26, size=patch.shape, dtype=np.int16)
    roof: np.ndarray = np.clip(patch.astype(np.int16) + noise, 0, 255).astype(np.uint8)
    return roof


class SimRenderer:
    """Draws frames for one camera over one ground; ``render`` is pure given the pose and time."""

    def __init__(self, camera: PinholeCamera, ground: GroundTexture, targets: list[GroundTarget] | None = None,
                 noise_sigma: float = 0.0, seed: int = 0, marker: GroundMarker | None = None) -> None:
        self.camera, self.ground = camera, ground
        self.targets = targets or []
        self.marker = marker
        self._patch = _target_patch(seed)
        h, w = camera.height, camera.width
        self._u, self._v = np.meshgrid(np.arange(w, dtype=np.float32), np.arange(h, dtype=np.float32))
        rng = np.random.default_rng(seed + 1)
        noise = [rng.normal(0, noise_sigma, size=(h, w, 3)) for _ in range(4)] if noise_sigma > 0 else []
        self._noise = [(np.clip(n, 0, 255).astype(np.uint8), np.clip(-n, 0, 255).astype(np.uint8)) for n in noise]

    def render(self, pose: Pose, t: float = 0.0, index: int = 0) -> np.ndarray:
        """A new BGR frame of ``pose`` at time ``t``; ``index`` picks the noise pattern."""
        image = self._ground(pose)
        self._sky(image, pose)
        if self.marker is not None:
            self._draw_marker(image, pose, self.marker)
        for target in self.targets:
            self._draw_target(image, pose, target, t)
        if self._noise:
            plus, minus = self._noise[index % len(self._noise)]
            cv2.add(image, plus, dst=image)
            cv2.subtract(image, minus, dst=image)
        return image

    def _ground(self, pose: Pose) -> np.ndarray:
        cam, ground = self.camera, self.ground
        # The ground repeats every period: move the camera into the first period (same picture).
        period = ground.period_m
        local = Pose(pose.n - period * round(pose.n / period), pose.e - period * round(pose.e / period), pose.d,
                     pose.roll, pose.pitch, pose.yaw)
        gsd = (ground_sample_distance(local, cam, (cam.width / 2, cam.height / 2))
               or ground_sample_distance(local, cam, (cam.width / 2, cam.height - 1)) or ground.metres_per_px)
        level = ground.level_for(gsd)
        image_from_texture = ground_to_image(local, cam) @ np.linalg.inv(ground.ground_to_texture(level))
        return cv2.warpPerspective(ground.levels[level], image_from_texture, (cam.width, cam.height),
                                   flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_WRAP)

    def _sky(self, image: np.ndarray, pose: Pose) -> None:
        a, b, c = ray_down_coefficients(pose, self.camera)
        w, h = self.camera.width - 1, self.camera.height - 1
        corners = [a * u + b * v + c for u, v in ((0, 0), (w, 0), (0, h), (w, h))]
        scale = float(np.linalg.norm([a, b])) * max(w, h) + abs(c)  # bounds |ray| to normalize the test
        if min(corners) > HORIZON_MIN_DOWN * scale:
            return
        down = a * self._u + b * self._v + c
        image[down <= HORIZON_MIN_DOWN * scale] = SKY_BGR

    def _draw_target(self, image: np.ndarray, pose: Pose, target: GroundTarget, t: float) -> None:
        self._paste(image, pose, self._patch, target.corners(t))

    def _draw_marker(self, image: np.ndarray, pose: Pose, marker: GroundMarker) -> None:
        quad = self._project(pose, marker.patch_corners())
        if quad is not None:
            side = float(np.max(np.linalg.norm(quad - np.roll(quad, 1, axis=0), axis=1)))
            self._paste(image, pose, marker.patch(side), marker.patch_corners(), quad)

    def _project(self, pose: Pose, ground_corners: np.ndarray) -> np.ndarray | None:
        """Image pixels of ground corners (n, e); None when one is behind the camera."""
        homogeneous = np.column_stack([ground_corners, np.ones(len(ground_corners))])
        projected = homogeneous @ ground_to_image(pose, self.camera).T
        if np.any(projected[:, 2] <= 1e-6):
            return None
        pixels: np.ndarray = projected[:, :2] / projected[:, 2:]
        return pixels

    def _paste(self, image: np.ndarray, pose: Pose, patch: np.ndarray, ground_corners: np.ndarray,
               quad: np.ndarray | None = None) -> None:
        """Draw ``patch`` (its corners: top-left, top-right, bottom-right, bottom-left) onto ``ground_corners``."""
        quad = self._project(pose, ground_corners) if quad is None else quad
        if quad is None:
            return
        x0, y0 = np.floor(quad.min(axis=0)).astype(int)
        x1, y1 = np.ceil(quad.max(axis=0)).astype(int) + 1
        x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, self.camera.width), min(y1, self.camera.height)
        if x1 <= x0 or y1 <= y0:
            return
        ph, pw = patch.shape[:2]
        # Pixel centres are whole numbers (OpenCV's, as in K): the patch's outer edges are half a pixel out.
        src = np.array([[-0.5, -0.5], [pw - 0.5, -0.5], [pw - 0.5, ph - 0.5], [-0.5, ph - 0.5]], np.float32)
        matrix = cv2.getPerspectiveTransform(src, (quad - (x0, y0)).astype(np.float32))
        size = (x1 - x0, y1 - y0)
        warped = cv2.warpPerspective(patch, matrix, size, flags=cv2.INTER_LINEAR)
        mask = cv2.warpPerspective(np.full((ph, pw), 255, np.uint8), matrix, size, flags=cv2.INTER_LINEAR)
        roi = image[y0:y1, x0:x1]
        np.copyto(roi, warped, where=mask[..., None] > 127)
