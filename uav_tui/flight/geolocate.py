"""Where a pixel is on the ground: the centre of ``box`` projected onto flat ground, with an uncertainty.

The ray through the pixel (the frame's camera model: intrinsics, distortion, mounting) is turned into
NED by the vehicle's attitude (yaw, pitch, roll, ZYX as MAVLink reports them) and intersected with a
horizontal plane ``height_m`` below the vehicle. Latitude and longitude follow by the flat-earth
approximation around the vehicle (mean earth radius: off by < 0.5 % of the distance, centimetres at the
ranges a camera sees a target). Pure scalar math (no NumPy on the path): about 20 µs a box, uncertainty
included (``scripts/bench_geolocation.py``).

The height above the ground is, first found: a downward rangefinder's, tilt-corrected, when the autopilot reports
one in range (``rangefinder_m``); the autopilot's height above the terrain (``terrain_height_m``: PX4's ALTITUDE
``bottom_clearance`` or ArduPilot's TERRAIN_REPORT); else the height above home (right on flat ground around
home). A rangefinder or terrain reading older than :data:`READING_MAX_AGE_S` at the capture is not
used (``GeoFix.height_note`` says so); which one was used is ``GeoFix.height_from``.

The uncertainty is the horizontal displacement the assumed 1-sigma errors below cause, each found by
projecting again with that one input off by its sigma, added in quadrature. It covers the attitude and
the height only: the vehicle's own position error (GPS: 1-3 m) adds to it one for one.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from controllers.base import RECEIVE_STAMPS
from uav_tui.flight.telemetry_sanity import implausible
from uav_values.camera import CameraModel

EARTH_RADIUS_M = 6_371_000.0
"""Mean earth radius of the flat-earth conversion (the built-in simulator uses the same)."""

ATTITUDE_SIGMA_DEG = 1.0
"""Assumed 1-sigma error of roll and pitch: a multicopter EKF's attitude, the camera's mounting and the
timing between frame and telemetry together (0.2-0.5 deg for the EKF alone)."""

YAW_SIGMA_DEG = 2.0
"""Assumed 1-sigma error of the heading: magnetometer-based yaw is the worst-known angle."""

HEIGHT_SIGMA_M = 0.5
"""Assumed 1-sigma error of the height above home as the height above the ground: barometric height over a
flight on flat ground (terrain that is not flat is worse and not covered)."""

RANGEFINDER_SIGMA_M = 0.1
"""Assumed 1-sigma error of a downward rangefinder's height: a few centimetres of the sensor's, plus ground
that is not quite flat between the vehicle and the target."""

TERRAIN_SIGMA_M = 2.0
"""Assumed 1-sigma error of the autopilot's height above the terrain: PX4 fuses a range sensor (decimetres), but
ArduPilot's comes from its terrain database (SRTM, metres of vertical error) and its AMSL altitude."""

READING_MAX_AGE_S = 0.5
"""A rangefinder or terrain reading older than this at the frame's capture is not used. Both are streamed at 10 Hz
(DISTANCE_SENSOR and ALTITUDE asked for at 10 Hz; ArduPilot's streams, TERRAIN_REPORT among them, at 10 Hz): 0.5 s
is five readings missed, a sensor or a link that stopped. And climbing or descending at 1 m/s, a reading 0.5 s old
is off by 0.5 m, :data:`HEIGHT_SIGMA_M`: beyond that the height above home is no worse."""

FROM_RANGEFINDER = "rangefinder"
FROM_TERRAIN = "terrain"
FROM_HOME = "home"
HEIGHT_SIGMAS = {FROM_RANGEFINDER: RANGEFINDER_SIGMA_M, FROM_TERRAIN: TERRAIN_SIGMA_M, FROM_HOME: HEIGHT_SIGMA_M}
"""Where the height above the ground came from (``GeoFix.height_from``, frames.csv ``target_height_from``)
and its assumed 1-sigma error."""

_READINGS = ((FROM_RANGEFINDER, "rangefinder_m"), (FROM_TERRAIN, "terrain_height_m"))
"""The readings of the height above the ground, best first: (source, telemetry field)."""

MIN_DEPRESSION_DEG = 1.0
"""A ray less than this far below the horizontal (the ground more than ~57 heights away, or sky) is not
located: status ``horizon``."""

OK = "ok"
NO_BOX = ""
"""The processor reported no box: nothing to locate (an empty status)."""
NO_CAMERA = "no_camera"
"""No camera model for the frame (a source without one and no ``camera_hfov`` / calibration set)."""
NO_POSITION = "no_position"
"""No latitude/longitude (no GPS fix yet, or no flight controller), or one that cannot be true (latitude 91)."""
NO_ATTITUDE = "no_attitude"
NO_HEIGHT = "no_height"
"""No height above the ground from the autopilot (neither rangefinder nor height above home), or one that cannot
be true (at or below the ground, above :data:`~uav_tui.flight.telemetry_sanity.MAX_ALTITUDE_M`)."""
HORIZON = "horizon"
"""The box's centre is at or above the horizon (see :data:`MIN_DEPRESSION_DEG`): no ground point."""

STATUSES = (OK, NO_BOX, NO_CAMERA, NO_POSITION, NO_ATTITUDE, NO_HEIGHT, HORIZON)
_WHY = {NO_POSITION: "no GPS position", NO_ATTITUDE: "no attitude", NO_HEIGHT: "no height",
        HORIZON: "at or above the horizon"}
"""What the status shows when a box is not located. Without a camera model it shows nothing: the event log says
``no camera model`` once, and a tracker on a camera without one should not carry a warning on every line."""


@dataclass(frozen=True, slots=True)
class GeoFix:
    """A box's ground position, or why there is none (``status``; the numbers are None unless ``ok``).

    ``north_m``/``east_m`` are from the vehicle to the target, ``height_m`` the vehicle's height above it
    (``height_from``: a key of :data:`HEIGHT_SIGMAS`; ``height_note``: why a better height was not used, e.g.
    ``rangefinder 0.8 s old``), ``alt_m`` is the ground's altitude AMSL (None when the autopilot reports no AMSL
    altitude).
    """

    status: str
    lat_deg: float | None = None
    lon_deg: float | None = None
    alt_m: float | None = None
    uncertainty_m: float | None = None
    north_m: float | None = None
    east_m: float | None = None
    height_m: float | None = None
    height_from: str = ""
    height_note: str = ""

    @property
    def distance_m(self) -> float | None:
        """Horizontal distance from the vehicle to the target."""
        return None if self.north_m is None or self.east_m is None else math.hypot(self.north_m, self.east_m)

    @property
    def range_m(self) -> float | None:
        """Straight-line distance from the vehicle to the target (MAVLink's ``dist``)."""
        if self.distance_m is None or self.height_m is None:
            return None
        return math.hypot(self.distance_m, self.height_m)

    @property
    def bearing_deg(self) -> float | None:
        """True bearing from the vehicle to the target, 0..360 degrees."""
        if self.north_m is None or self.east_m is None:
            return None
        return math.degrees(math.atan2(self.east_m, self.north_m)) % 360.0


def describe(fix: GeoFix) -> str:
    """One line for the status: ``47.397810,8.545600 12 m at 045 deg +-0.6 m``, why not, or "" (no box or camera)."""
    if not (where := range_and_bearing(fix)):
        return f"not located: {_WHY[fix.status]}" if fix.status in _WHY else ""
    note = f" (height from {fix.height_from}: {fix.height_note})" if fix.height_note else ""
    return f"{fix.lat_deg:.6f},{fix.lon_deg:.6f} {where} +-{fix.uncertainty_m:.1f} m{note}"


def range_and_bearing(fix: GeoFix) -> str:
    """``12 m at 045 deg`` from the vehicle, or "" when ``fix`` has no position."""
    if fix.status != OK or fix.distance_m is None or fix.bearing_deg is None:
        return ""
    return f"{fix.distance_m:.0f} m at {round(fix.bearing_deg) % 360:03d} deg"


def locate(camera: CameraModel | None, box: tuple[float, float, float, float] | None, *, roll_deg: float | None,
           pitch_deg: float | None, yaw_deg: float | None, lat_deg: float | None, lon_deg: float | None,
           height_m: float | None, abs_alt_m: float | None = None, height_from: str = FROM_HOME,
           height_note: str = "") -> GeoFix:
    """The ground position of the centre of ``box`` (x, y, w, h in frame pixels) seen from this pose.

    Args:
        camera: the frame's camera model (None: status ``no_camera``).
        roll_deg, pitch_deg, yaw_deg: the vehicle's attitude at the capture.
        lat_deg, lon_deg: the vehicle's position at the capture.
        height_m: the vehicle's height above the ground (above it: > 0).
        abs_alt_m: the vehicle's altitude AMSL, for the target's altitude (optional).
        height_from: where ``height_m`` came from (a key of :data:`HEIGHT_SIGMAS`): its assumed error.
        height_note: why a better height was not used (kept in the fix).

    Values that cannot be true (:mod:`~uav_tui.flight.telemetry_sanity`: a recording's telemetry is checked here, not
    at the vehicle's boundary) count as not known.
    """
    if box is None:
        return GeoFix(NO_BOX)
    if camera is None:
        return GeoFix(NO_CAMERA)
    if not _possible(lat_deg=lat_deg, lon_deg=lon_deg):
        return GeoFix(NO_POSITION)
    if not _possible(roll_deg=roll_deg, pitch_deg=pitch_deg, yaw_deg=yaw_deg):
        return GeoFix(NO_ATTITUDE)
    if not _possible(rel_alt_m=height_m) or height_m <= 0:  # type: ignore[operator]
        return GeoFix(NO_HEIGHT)
    x, y, w, h = box
    ray = _body_ray(camera, x + w / 2 - 0.5, y + h / 2 - 0.5)  # the box's centre in OpenCV's pixel convention
    offset = camera.mount.offset_m
    args = (ray, offset, roll_deg, pitch_deg, yaw_deg, height_m)
    found = _ground(*args)  # type: ignore[arg-type]
    if found is None:
        return GeoFix(HORIZON)
    spread = 0.0
    height_sigma = HEIGHT_SIGMAS[height_from]
    for index, sigma in ((2, ATTITUDE_SIGMA_DEG), (3, ATTITUDE_SIGMA_DEG), (4, YAW_SIGMA_DEG), (5, height_sigma)):
        moved = _moved(args, index, sigma, found)
        if moved is None:
            return GeoFix(HORIZON)
        spread += moved
    north, east = found
    lat = lat_deg + math.degrees(north / EARTH_RADIUS_M)  # type: ignore[operator]
    lon = lon_deg + math.degrees(east / (EARTH_RADIUS_M * math.cos(math.radians(lat_deg))))  # type: ignore[arg-type, operator]
    alt = abs_alt_m - height_m if _possible(abs_alt_m=abs_alt_m) else None  # type: ignore[operator]
    return GeoFix(OK, lat, lon, alt, math.sqrt(spread), north, east, height_m, height_from, height_note)


def locate_row(camera: CameraModel | None, box: tuple[float, float, float, float] | None,
               telemetry: Mapping[str, Any], *, at_ns: int | None = None) -> GeoFix:
    """:func:`locate` with telemetry fields by name (a frame row's interpolated values, ``Telemetry`` as a dict).

    The height above the ground is from :func:`ground_height`; ``at_ns`` is the frame's capture (monotonic ns), for
    the age of the readings (None: not judged). A camera on the gimbal (``camera.mount.gimbal``) looks with the
    gimbal's attitude (``gimbal_roll_deg``, ``gimbal_pitch_deg``, ``gimbal_yaw_deg``; status ``no_attitude`` while
    there is none), not the vehicle's.
    """
    height, source, note = ground_height(telemetry, at_ns)
    looking = ("gimbal_roll_deg", "gimbal_pitch_deg", "gimbal_yaw_deg") if camera is not None and camera.mount.gimbal \
        else ("roll_deg", "pitch_deg", "yaw_deg")
    roll, pitch, yaw = (telemetry.get(name) for name in looking)
    return locate(camera, box, roll_deg=roll, pitch_deg=pitch, yaw_deg=yaw,
                  lat_deg=telemetry.get("lat_deg"), lon_deg=telemetry.get("lon_deg"), height_m=height,
                  abs_alt_m=telemetry.get("abs_alt_m"), height_from=source, height_note=note)


def ground_height(telemetry: Mapping[str, Any], at_ns: int | None = None) -> tuple[float | None, str, str]:
    """``(height above the ground, where from, why a better one was not used)`` at the capture ``at_ns``.

    The rangefinder's (``rangefinder_m``, along the body's down axis, times the cosines of the vehicle's roll and
    pitch), else the autopilot's height above the terrain (``terrain_height_m``), each only if received
    (``rangefinder_t_ns``, ``terrain_t_ns``) at most :data:`READING_MAX_AGE_S` before ``at_ns``; else ``rel_alt_m``,
    the height above home.
    """
    roll: Any = telemetry.get("roll_deg")
    pitch: Any = telemetry.get("pitch_deg")
    stale = []
    for source, name in _READINGS:
        reading: Any = telemetry.get(name)
        if not _known(reading):
            continue
        received = telemetry.get(RECEIVE_STAMPS[name])
        age_s = (at_ns - received) / 1e9 if at_ns is not None and received is not None else 0.0
        if age_s > READING_MAX_AGE_S:
            stale.append(f"{source} {age_s:.1f} s old")
        elif source == FROM_TERRAIN:
            return reading, source, "; ".join(stale)
        elif _known(roll, pitch):
            return reading * math.cos(math.radians(roll)) * math.cos(math.radians(pitch)), source, ""
    return telemetry.get("rel_alt_m"), FROM_HOME, "; ".join(stale)


def _possible(**values: float | None) -> bool:
    """Every one of ``values`` (telemetry fields by name) known and possible."""
    return all(value is not None and not implausible(name, value) for name, value in values.items())


def _known(*values: float | None) -> bool:
    return all(value is not None and math.isfinite(value) for value in values)


def _body_ray(camera: CameraModel, u: float, v: float) -> tuple[float, float, float]:
    """The (unnormalized) ray through pixel ``(u, v)`` in the body frame (FRD)."""
    if camera.distortion:
        x, y, z = (float(c) for c in camera.pixel_to_ray(u, v))
    else:
        x, y, z = (u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0
    t = math.radians(camera.mount.tilt_deg)  # the camera's axes in FRD, as CameraModel.rotation_body_camera
    ct, st = math.cos(t), math.sin(t)
    return -st * y + ct * z, x, ct * y + st * z


def _ground(ray: tuple[float, float, float], offset: tuple[float, float, float], roll: float, pitch: float,
            yaw: float, height: float) -> tuple[float, float] | None:
    """(north, east) metres from the vehicle where ``ray`` (FRD) meets the ground ``height`` below it."""
    r, p, y = math.radians(roll), math.radians(pitch), math.radians(yaw)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    rows = ((cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),  # Rz(yaw) Ry(pitch) Rx(roll): FRD -> NED
            (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
            (-sp, cp * sr, cp * cr))
    dn, de, dd = (row[0] * ray[0] + row[1] * ray[1] + row[2] * ray[2] for row in rows)
    on, oe, od = (row[0] * offset[0] + row[1] * offset[1] + row[2] * offset[2] for row in rows)
    if dd <= math.sin(math.radians(MIN_DEPRESSION_DEG)) * math.sqrt(dn * dn + de * de + dd * dd):
        return None
    scale = (height - od) / dd
    return on + scale * dn, oe + scale * de


def _moved(args: tuple[Any, ...], index: int, sigma: float, found: tuple[float, float]) -> float | None:
    """Squared horizontal shift of the ground point when ``args[index]`` is off by ``sigma`` (either way)."""
    for step in (sigma, -sigma):
        changed = list(args)
        changed[index] += step
        moved = _ground(*changed)
        if moved is not None:
            return (moved[0] - found[0]) ** 2 + (moved[1] - found[1]) ** 2
    return None
