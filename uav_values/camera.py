"""The camera model: what a pixel means. Intrinsics (OpenCV's pinhole with distortion) and the mounting.

Frames: the camera frame is OpenCV's (x right, y down in the image, z along the optical axis); the body
frame is FRD (forward, right, down). The camera is fixed to the body, tilted down from the nose by
``Mount.tilt_deg`` (90: looking straight down, the top of the image towards the nose; 0: looking ahead),
at ``Mount.offset_m`` (FRD metres) from the vehicle's centre. ``sim:`` renders with the same conventions.

Pixels are OpenCV's: the centre of the top-left pixel is ``(0, 0)``; its distortion model is OpenCV's, computed
in NumPy (:mod:`uav_values.lens`), so a model needs no OpenCV.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from uav_values.camera_plausibility import implausibility
from uav_values.lens import Lens

MOUNTS = {"down": 90.0, "forward": 0.0}
"""Named mounts and their tilt below the vehicle's nose, degrees."""

GIMBAL = "gimbal"
"""The named mount of a camera on the gimbal (:attr:`Mount.gimbal`)."""


class CameraModelError(ValueError):
    """A camera model cannot be built: a calibration file that does not parse, or is for another resolution.

    The platform counts it among its known errors (:data:`uav_tui.errors.KNOWN_ERRORS`); a configuration value
    that names such a file is a ``ConfigError`` (the ValueError's message, with the key).
    """

    key = "camera"


@dataclass(frozen=True)
class Mount:
    """How the camera sits on the vehicle: tilt below the nose (degrees) and offset from its centre (FRD, m).

    ``gimbal``: the camera rides the vehicle's gimbal, so its attitude is the gimbal's (the ``gimbal_*`` telemetry:
    pitch from the horizon, yaw from north), not the vehicle's; ``tilt_deg`` is then 0, the gimbal's forward axis.
    """

    tilt_deg: float = 90.0
    offset_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    gimbal: bool = False

    @classmethod
    def parse(cls, mount: str, offset: str = "") -> Mount:
        """``down``, ``forward``, ``gimbal`` or a tilt in degrees below the nose (``45``); ``offset`` ``F,R,D``
        metres or empty.

        Raises ValueError with what is expected.
        """
        text = mount.strip().lower()
        on_gimbal = text == GIMBAL
        if on_gimbal:
            text = "forward"
        try:
            tilt = MOUNTS[text] if text in MOUNTS else float(text)
        except ValueError:
            raise ValueError(f"mount {mount!r} must be down, forward, gimbal or a tilt below the nose in degrees "
                             "(90 = down, 0 = forward)") from None
        if not -90 <= tilt <= 180:
            raise ValueError(f"mount tilt {tilt:g} must be -90..180 degrees below the nose (90 = down)")
        parts = [p for p in offset.replace(" ", "").split(",") if p] if offset.strip() else ["0", "0", "0"]
        try:
            values = tuple(float(p) for p in parts)
        except ValueError:
            values = ()
        if len(values) != 3 or not all(math.isfinite(v) and abs(v) <= 10 for v in values):
            raise ValueError(f"offset {offset!r} must be F,R,D in metres from the vehicle's centre, each within "
                             "10 m (e.g. 0.1,0,0.05)")
        return cls(tilt, values, on_gimbal)

    def describe(self) -> str:
        tilted = f"tilted {self.tilt_deg:g} deg below the nose"
        name = GIMBAL if self.gimbal else next((n for n, t in MOUNTS.items() if t == self.tilt_deg), tilted)
        offset = "" if not any(self.offset_m) else " at {:g},{:g},{:g} m (FRD)".format(*self.offset_m)
        return name + offset


@dataclass(frozen=True)
class CameraModel:
    """One camera's intrinsics, image size and mounting; ``origin`` says where they came from.

    Built by :meth:`from_hfov`, :meth:`sources.calibration.load_model` or a source (``sim:`` states its own).
    Each call is a few microseconds without distortion; with distortion undistorting a pixel iterates (tens of µs;
    ``scripts/bench_camera_model.py``).
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    distortion: tuple[float, ...] = ()
    """OpenCV's coefficients (k1, k2, p1, p2[, k3[, k4, k5, k6 ...]]); empty: none."""
    mount: Mount = field(default_factory=Mount)
    origin: str = ""
    """Where the model came from, as shown to the user (``sim: renderer (exact)``, a file and its RMS ...)."""
    rms_px: float | None = None
    """The calibration's RMS reprojection error in pixels, when calibrated."""
    _k: np.ndarray = field(init=False, repr=False, compare=False)
    _lens: Lens | None = field(init=False, repr=False, compare=False)
    _r: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        numbers = (self.fx, self.fy, self.cx, self.cy, *self.distortion)
        if self.width <= 0 or self.height <= 0 or not all(math.isfinite(v) for v in numbers):
            raise CameraModelError(f"camera model: size {self.width}x{self.height} and intrinsics must be positive, "
                                   "finite numbers")
        if self.fx <= 0 or self.fy <= 0:
            raise CameraModelError(f"camera model: focal lengths fx={self.fx:g}, fy={self.fy:g} must be > 0")
        if len(self.distortion) not in (0, 4, 5, 8, 12, 14):
            raise CameraModelError(f"camera model: {len(self.distortion)} distortion coefficients; OpenCV takes "
                                   "4, 5, 8, 12 or 14")
        if reason := implausibility(self.width, self.height, self.fx, self.fy, self.cx, self.cy, self.distortion):
            raise CameraModelError(f"camera model: {reason}")
        k = np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])
        r = rotation_body_camera(self.mount.tilt_deg)
        k.flags.writeable = r.flags.writeable = False
        object.__setattr__(self, "_k", k)
        object.__setattr__(self, "_lens", Lens(self.fx, self.fy, self.cx, self.cy, self.distortion)
                           if any(self.distortion) else None)
        object.__setattr__(self, "_r", r)

    @classmethod
    def from_hfov(cls, width: int, height: int, hfov_deg: float, mount: Mount | None = None, *,
                  origin: str = "") -> CameraModel:
        """An ideal camera (square pixels, centred, no distortion) with a horizontal field of view of ``hfov_deg``."""
        if not 1 <= hfov_deg <= 170:
            raise CameraModelError(f"camera model: hfov {hfov_deg:g} must be 1..170 degrees")
        f = (width / 2) / math.tan(math.radians(hfov_deg) / 2)
        return cls(width, height, f, f, width / 2, height / 2, (), mount or Mount(),
                   origin or f"horizontal field of view {hfov_deg:g} deg (no distortion)")

    def to_dict(self) -> dict[str, Any]:
        """Plain numbers and text (``run.json``); :meth:`from_dict` reads it back."""
        return {"width": self.width, "height": self.height, "fx": self.fx, "fy": self.fy, "cx": self.cx,
                "cy": self.cy, "distortion": list(self.distortion), "tilt_deg": self.mount.tilt_deg,
                "offset_m": list(self.mount.offset_m), "gimbal": self.mount.gimbal, "origin": self.origin,
                "rms_px": self.rms_px}

    @classmethod
    def from_dict(cls, data: dict[str, Any], origin: str | None = None) -> CameraModel:
        """The model :meth:`to_dict` wrote; CameraModelError when a value is missing or wrong."""
        try:
            forward, right, down = (float(v) for v in data["offset_m"])
            mount = Mount(float(data["tilt_deg"]), (forward, right, down), bool(data.get("gimbal", False)))
            rms = data.get("rms_px")
            return cls(int(data["width"]), int(data["height"]), float(data["fx"]), float(data["fy"]),
                       float(data["cx"]), float(data["cy"]), tuple(float(c) for c in data["distortion"]), mount,
                       str(data["origin"]) if origin is None else origin, None if rms is None else float(rms))
        except (KeyError, TypeError, ValueError) as exc:
            raise CameraModelError(f"camera model: a value is missing or wrong ({exc})") from None

    # -- what the numbers are ---------------------------------------------------------------------

    @property
    def matrix(self) -> np.ndarray:
        """K, 3x3 (read-only)."""
        return self._k

    @property
    def distortion_array(self) -> np.ndarray:
        """The distortion coefficients as OpenCV takes them (zeros when there is none)."""
        return np.array(self.distortion, float) if self._lens is not None else np.zeros(5)

    @property
    def rotation_body_camera(self) -> np.ndarray:
        """The camera's axes (columns x, y, z) in the body frame (FRD), 3x3 (read-only)."""
        return self._r

    @property
    def hfov_deg(self) -> float:
        """Horizontal field of view through the principal point, ignoring distortion."""
        return math.degrees(math.atan(self.cx / self.fx) + math.atan((self.width - self.cx) / self.fx))

    def describe(self) -> str:
        """One line for the status and the event log."""
        rms = f", RMS {self.rms_px:.2f} px" if self.rms_px is not None else ""
        return (f"{self.width}x{self.height}, fx {self.fx:.1f} fy {self.fy:.1f} px (hfov {self.hfov_deg:.1f} deg)"
                f"{', distorted' if self._lens is not None else ''}, {self.mount.describe()}; {self.origin}{rms}")

    def check_size(self, width: int, height: int) -> None:
        """Raise CameraModelError (saying what to do) when the camera's frames are not the model's size."""
        if (width, height) != (self.width, self.height):
            raise CameraModelError(
                f"the camera model is for {self.width}x{self.height} frames but the camera gives {width}x{height} "
                f"({self.origin}): calibrate at this size (uav-tui calibrate --source URI) or set the camera's "
                "width/height to match")

    # -- pixels and rays ------------------------------------------------------------------------

    def pixel_to_ray(self, u: float, v: float) -> np.ndarray:
        """The unit ray (camera frame) that pixel ``(u, v)`` sees, distortion removed."""
        if self._lens is None:
            x, y = (u - self.cx) / self.fx, (v - self.cy) / self.fy
        else:
            x, y = self._lens.undistort_point(float(u), float(v))
        norm = math.sqrt(x * x + y * y + 1.0)
        return np.array([x / norm, y / norm, 1.0 / norm])

    def pixels_to_rays(self, pixels: np.ndarray) -> np.ndarray:
        """Unit rays (N x 3, camera frame) for pixels (N x 2)."""
        points = np.asarray(pixels, float).reshape(-1, 2)
        xy = (points - (self.cx, self.cy)) / (self.fx, self.fy) if self._lens is None else self._lens.undistort(points)
        rays = np.column_stack([xy, np.ones(len(xy))])
        unit: np.ndarray = rays / np.linalg.norm(rays, axis=1, keepdims=True)
        return unit

    def ray_to_pixel(self, ray: np.ndarray) -> tuple[float, float] | None:
        """The pixel (distorted, as the camera shows it) a camera-frame ray falls on; None behind the camera."""
        x, y, z = (float(c) for c in ray)
        if z <= 1e-9:
            return None
        if self._lens is None:
            return self.fx * x / z + self.cx, self.fy * y / z + self.cy
        return self._lens.project(x, y, z)

    def rays_to_pixels(self, rays: np.ndarray) -> np.ndarray:
        """Pixels (N x 2) for camera-frame rays (N x 3) in front of the camera (z > 0)."""
        rays = np.asarray(rays, float).reshape(-1, 3)
        if self._lens is None:
            pinhole: np.ndarray = rays[:, :2] / rays[:, 2:] * (self.fx, self.fy) + (self.cx, self.cy)
            return pinhole
        return np.column_stack(self._lens.project(rays[:, 0], rays[:, 1], rays[:, 2]))

    def angles(self, u: float, v: float) -> tuple[float, float]:
        """(right, down) angles in radians of pixel ``(u, v)`` off the optical axis (LANDING_TARGET's angle_x, _y)."""
        x, y, z = self.pixel_to_ray(u, v)
        return math.atan2(x, z), math.atan2(y, z)

    def ray_in_body(self, ray: np.ndarray) -> np.ndarray:
        """A camera-frame ray in the body frame (FRD)."""
        body: np.ndarray = self._r @ np.asarray(ray, float)
        return body


def rotation_body_camera(tilt_deg: float) -> np.ndarray:
    """Camera axes (columns x, y, z) expressed in the body frame for a camera tilted down by ``tilt_deg``."""
    t = math.radians(tilt_deg)
    z = np.array([math.cos(t), 0.0, math.sin(t)])
    x = np.array([0.0, 1.0, 0.0])
    return np.column_stack([x, np.cross(z, x), z])
