"""What uav-tui can be told: one frozen dataclass per ``uav.toml`` section, each key with its help, range and
parser (read by :mod:`~uav_tui.config.loading` and :mod:`~uav_tui.config.flags`)."""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import MISSING, dataclass, field
from enum import StrEnum
from typing import TYPE_CHECKING, Any

from controllers.sim.geo import Home, parse_wind
from processors.frame_telemetry import DEFAULT_SAVE_MAX_HZ
from uav_tui.errors import ConfigError
from uav_tui.token_strength import GENERATE_TOKEN, MIN_TOKEN_BITS

if TYPE_CHECKING:
    from uav_values.camera import CameraModel


def _key(help: str, *, minimum: float | None = None, maximum: float | None = None, default: Any = MISSING,
         factory: Any = MISSING, parse: Callable[[str], Any] | None = None, metavar: str | None = None) -> Any:
    metadata = {"help": help, "min": minimum, "max": maximum, "parse": parse, "metavar": metavar}
    if factory is not MISSING:
        return field(default_factory=factory, metadata=metadata)
    return field(default=default, metadata=metadata)


@dataclass(frozen=True)
class SafetyConfig:
    """Limits the platform enforces on every vector (the manual's safety rules, docs/safety.md)."""

    max_speed: float = _key("largest |vx|, |vy| executed, m/s", minimum=0.05, maximum=20, default=1.0)
    max_t: float = _key("longest vector duration, s; also the processor-stall limit", minimum=0.1, maximum=10,
                        default=2.0)
    max_frame_age: float = _key("a vector from a frame older than this (s) is not executed", minimum=0.01,
                                maximum=5, default=0.5)
    link_timeout: float = _key("heartbeat age (s) after which the link counts as lost", minimum=0.2, maximum=30,
                               default=1.5)
    camera_stall: float = _key("no new frame for this long (s) stops autonomy", minimum=0.1, maximum=30,
                               default=1.0)
    max_processor_errors: int = _key("consecutive processor exceptions that stop autonomy", minimum=1,
                                     maximum=1000, default=3)
    takeoff_alt: float = _key("default takeoff altitude, m", minimum=1, maximum=120, default=5.0)
    tune_autopilot_failsafe: bool = _key("at connect, set the autopilot's offboard-loss failsafe (COM_OF_LOSS_T, "
                                         "COM_OBL_RC_ACT, GUID_TIMEOUT, GUID_OPTIONS) when it would fly a dead "
                                         "platform's last command longer than max_t + 0.5 s or not hold without a "
                                         "pilot; off: refuse autonomy instead",
                                         default=True)
    max_altitude: float = _key("highest altitude a takeoff command may ask for, m", minimum=1, maximum=10000,
                               default=120.0)
    max_orbit_radius: float = _key("largest orbit radius a command may ask for, m", minimum=1, maximum=10000,
                                   default=100.0)
    max_orbit_speed: float = _key("largest orbit speed a command may ask for, m/s", minimum=0.1, maximum=30,
                                  default=5.0)

    def __post_init__(self) -> None:
        if self.takeoff_alt > self.max_altitude:
            raise ConfigError(f"takeoff_alt = {self.takeoff_alt:g} is above max_altitude = {self.max_altitude:g}; "
                              "lower takeoff_alt or raise max_altitude", key="takeoff_alt")


ENVELOPE_ACTIONS = ("hold", "rtl", "land")
"""What a breach of the envelope makes the vehicle do (``*_action`` keys)."""


LOST_ACTIONS = (*ENVELOPE_ACTIONS, "last_seen")
"""``lost_action`` may also fly back to where the target was last seen."""


def _one_of(choices: tuple[str, ...]) -> Callable[[str], None]:
    def check(text: str) -> None:
        if text not in choices:
            raise ValueError(f"must be one of {', '.join(choices)}, got {text!r}")
    return check


_action = _one_of(ENVELOPE_ACTIONS)


def _polygon_file(path: str) -> None:
    if path.strip():
        from uav_tui.flight.envelope_shape import read_polygon

        read_polygon(path)


@dataclass(frozen=True)
class EnvelopeConfig:
    """Where, how high and how long the processor may fly the vehicle (docs/safety.md, "The envelope")."""

    radius_m: float = _key("horizontal distance from home a vector may take the vehicle, m (0 = off)", minimum=0,
                           maximum=100000, default=0.0)
    polygon: str = _key("GeoJSON file with the one Polygon the vehicle must stay in (empty = off)", default="",
                        parse=_polygon_file, metavar="FILE")
    response_lag_s: float = _key("how far a vector carries on after it ends (the vehicle's braking), s of its "
                                 "velocity, added to each vector's predicted end point", minimum=0, maximum=5,
                                 default=0.6)
    boundary_band_m: float = _key("within this distance of the boundary a vector's outward component is removed "
                                  "(it slides along), m", minimum=0, maximum=100, default=0.5)
    min_height_m: float = _key("lowest height above the ground under autonomy, m (rangefinder, else the autopilot's "
                               "terrain height, else above home; 0 = off)", minimum=0, maximum=10000, default=0.0)
    max_height_m: float = _key("highest height above the ground under autonomy, m (0 = off)", minimum=0,
                               maximum=10000, default=0.0)
    min_home_height_m: float = _key("lowest height above home under autonomy, m (0 = off)", minimum=0,
                                    maximum=10000, default=0.0)
    max_home_height_m: float = _key("highest height above home under autonomy, m (0 = off)", minimum=0,
                                    maximum=10000, default=120.0)
    height_action: str = _key("what a vehicle outside the height band does: hold, rtl or land", default="hold",
                              parse=_action, metavar="hold|rtl|land")
    max_autonomy_s: float = _key("longest one engagement of autonomy, s (0 = off)", minimum=0, maximum=86400,
                                 default=0.0)
    time_action: str = _key("what the vehicle does when max_autonomy_s runs out: hold, rtl or land", default="hold",
                            parse=_action, metavar="hold|rtl|land")
    battery_floor_pct: float = _key("battery percentage below which autonomy ends (0 = off)", minimum=0,
                                    maximum=100, default=20.0)
    battery_floor_v: float = _key("battery voltage below which autonomy ends (0 = off)", minimum=0, maximum=100,
                                  default=0.0)
    battery_action: str = _key("what the vehicle does at the battery floor: hold, rtl or land", default="rtl",
                               parse=_action, metavar="hold|rtl|land")
    link_floor_pct: float = _key("link quality (the RC receiver's or a telemetry radio's signal, where the "
                                 "autopilot reports it) below which autonomy ends, percent (0 = off; unknown never "
                                 "ends it)", minimum=0, maximum=100, default=0.0)
    link_floor_s: float = _key("how long the link quality stays below link_floor_pct before autonomy ends, s",
                               minimum=0, maximum=60, default=2.0)
    link_action: str = _key("what the vehicle does at the link-quality floor: hold, rtl or land", default="rtl",
                            parse=_action, metavar="hold|rtl|land")
    lost_after_s: float = _key("the processor's target gone this long (no box and no vector after either) ends "
                               "autonomy, s (0 = off)", minimum=0, maximum=600, default=0.0)
    lost_action: str = _key("what the vehicle does when the target is lost: hold, rtl, land or last_seen (fly back "
                            "to where the vehicle was when the target was last reported, and hold)", default="hold",
                            parse=_one_of(LOST_ACTIONS), metavar="hold|rtl|land|last_seen")
    require_autopilot_fence: bool = _key("refuse autonomy unless the autopilot's own geofence is set up to act "
                                         "(ArduPilot FENCE_*, PX4 GF_*; read at connect)", default=False)

    def __post_init__(self) -> None:
        for low, high in (("min_height_m", "max_height_m"), ("min_home_height_m", "max_home_height_m")):
            floor, ceiling = getattr(self, low), getattr(self, high)
            if floor and ceiling and floor >= ceiling:
                raise ConfigError(f"envelope: {low} = {floor:g} is not below {high} = {ceiling:g}; lower the floor "
                                  "or raise the ceiling", key=low)


@dataclass(frozen=True)
class RecordingConfig:
    """The flight dataset written under ``runs_dir``."""

    record: bool = _key("record the run (telemetry, frames, events)", default=True)
    runs_dir: str = _key("folder that holds one sub-folder per run", default="runs")
    record_video: bool = _key("record the camera stream as one video with an index (video.ts, video.csv)",
                              default=True)
    record_every: int = _key("also save every Nth raw frame (0 = only frames the processor saves)", minimum=0,
                             maximum=100000, default=0)
    jpeg_quality: int = _key("JPEG quality of saved frames", minimum=10, maximum=100, default=90)
    save_max_hz: float = _key("tmMgr.save calls stored per second of the frames' time; more are dropped "
                              "with one warning (0 = no limit)", minimum=0, maximum=1000,
                              default=DEFAULT_SAVE_MAX_HZ)
    max_disk_mb: float = _key("stop saving frames when the run folder reaches this size (0 = no cap)",
                              minimum=0, maximum=1e7, default=0)
    min_free_mb: float = _key("stop saving frames when the disk has less free space than this", minimum=0,
                              maximum=1e7, default=200)


def _video_out(uri: str) -> None:
    if uri.strip():
        from uav_tui.web.rtp import Destination

        Destination.parse(uri)


def _rtsp_path(path: str) -> None:
    if not re.fullmatch(r"(/[A-Za-z0-9._~-]+)+", path):
        raise ValueError(f"video_rtsp_path {path!r} must be a path such as /video: '/' then letters, digits "
                         "and - . _ ~ (more parts after another '/')")


@dataclass(frozen=True)
class WebConfig:
    """The optional WebRTC side page."""

    web: bool = _key("serve the WebRTC page", default=False)
    web_host: str = _key("address the page binds to", default="0.0.0.0")
    web_port: int = _key("port of the page", minimum=1, maximum=65535, default=8080)
    web_token: str = _key(f"access token of letters, digits and - . _ ~ with at least {MIN_TOKEN_BITS} bits of "
                          f"entropy (make one: {GENERATE_TOKEN}); empty = a random one per start", default="")
    web_origins: str = _key("other page origins allowed to send commands, comma-separated, e.g. "
                            "https://gcs.local:8443 (the page's own origin is always allowed)", default="")
    web_width: int = _key("width of the streamed video, px", minimum=64, maximum=4096, default=640)
    web_fps: float = _key("frame rate of the streamed video", minimum=1, maximum=60, default=15)
    camera_mavlink: str = _key("MAVLink camera endpoint for ground-station click-to-track, e.g. "
                               "udpin:0.0.0.0:14580 (empty = off)", default="")
    video_out: str = _key("the processed video for a ground station, H.264 over RTP/UDP: rtp://HOST:PORT of the "
                          "ground station (QGroundControl listens on 5600; empty = off)", default="",
                          parse=_video_out, metavar="rtp://HOST:PORT")
    video_out_width: int = _key("width of the ground-station video, px", minimum=64, maximum=1920, default=640)
    video_out_fps: float = _key("frame rate of the ground-station video", minimum=1, maximum=60, default=15)
    video_out_kbps: int = _key("bit rate of the ground-station video, kbit/s (a telemetry-grade radio carries "
                               "about 1000)", minimum=50, maximum=20000, default=1000)
    video_rtsp_port: int = _key("the processed video as an RTSP stream: the TCP port its server listens on, "
                                "e.g. 8554 (0 = off); same size, rate and bit rate as video_out",
                                minimum=0, maximum=65535, default=0)
    video_rtsp_path: str = _key("the RTSP stream's path: rtsp://DRONE:PORT/PATH", default="/video",
                                parse=_rtsp_path, metavar="/PATH")


def _home(text: str) -> Home | None:
    return Home.parse(text) if text.strip() else None


@dataclass(frozen=True)
class SimConfig:
    """The built-in simulated vehicle (``fc = "sim"``); ``uav-tui sim`` takes the same options."""

    home: str = _key("where the simulated vehicle boots: LAT,LON,ALT (empty: PX4 SITL's Zurich home)", default="",
                     parse=_home, metavar="LAT,LON,ALT")
    wind: str = _key("steady wind on the simulated vehicle: N,E in m/s", default="0,0", parse=parse_wind,
                     metavar="N,E")
    noise: bool = _key("add sensor noise to the simulated vehicle's telemetry", default=False)
    seed: int = _key("random seed of the simulated vehicle's noise", minimum=0, maximum=2**31 - 1, default=0)
    battery_pct: float = _key("the simulated vehicle's battery charge at boot, percent", minimum=0, maximum=100,
                              default=100.0)
    battery_minutes: float = _key("minutes of flight the simulated vehicle's full battery lasts (it drains a tenth "
                                  "as fast on the ground)", minimum=0.1, maximum=1000, default=20.0)

    def vehicle(self) -> dict[str, Any]:
        """The arguments of :class:`controllers.sim.launcher.SimVehicle` these settings give."""
        battery = ("--battery", f"{self.battery_pct:g}", "--battery-minutes", f"{self.battery_minutes:g}")
        return {"home": _home(self.home), "wind": parse_wind(self.wind), "seed": self.seed, "noise": self.noise,
                "extra_args": battery}


def _calibration_file(path: str) -> None:
    if path.strip():
        from sources.calibration import read_calibration  # OpenCV: only when a file is configured

        read_calibration(path)


def _mount(mount: str, offset: str = "") -> Any:
    from uav_values.camera import Mount

    return Mount.parse(mount, offset)


@dataclass(frozen=True)
class CameraConfig:
    """The camera model of a source that does not state its own (``sim:`` and ``run:`` do): file, or field of view."""

    camera_calibration: str = _key("OpenCV calibration file (uav-tui calibrate writes one); empty: camera_hfov",
                                   default="", parse=_calibration_file, metavar="FILE")
    camera_hfov: float = _key("the camera's horizontal field of view, degrees, without a calibration file "
                              "(0 = unknown: no camera model)", minimum=0, maximum=170, default=0.0)
    camera_mount: str = _key("how the camera is mounted: down, forward, gimbal (on the vehicle's gimbal), or its "
                             "tilt below the nose in degrees", default="down", parse=_mount,
                             metavar="down|forward|gimbal|DEG")
    camera_offset: str = _key("where the camera is from the vehicle's centre: forward, right, down in metres",
                              default="0,0,0", parse=lambda text: _mount("down", text), metavar="F,R,D")

    def model(self, width: int, height: int) -> CameraModel | None:
        """The configured model for frames of ``width`` x ``height``; None when neither file nor hfov is given."""
        from sources.calibration import load_model
        from uav_values.camera import CameraModel

        mount = _mount(self.camera_mount, self.camera_offset)
        if self.camera_calibration.strip():
            return load_model(self.camera_calibration, mount)
        if self.camera_hfov > 0:
            return CameraModel.from_hfov(width, height, self.camera_hfov, mount,
                                         origin=f"camera_hfov {self.camera_hfov:g} deg (no distortion)")
        return None


@dataclass(frozen=True)
class Config:
    """Everything uav-tui can be told. The first three keys are the three plug-in levels."""

    source: str = _key("camera URI: file:PATH, synthetic:, usb:0, picam:0, rtsp://..., sim:", default="synthetic:")
    processor: str = _key("processor: short name, module:Class or path/file.py:Class", default="template")
    fc: str = _key("flight controller: MAVLink connection string, 'sim' (built-in vehicle) or 'none'",
                   default="none")
    connect_timeout: float = _key("seconds to wait for the autopilot's first heartbeat", minimum=0.5, maximum=300,
                                  default=10.0)
    processor_args: dict[str, Any] = _key("keyword arguments for the processor's constructor", factory=dict)
    isolation: str = _key("where the processor runs: 'process' (its own process: a hang or crash cannot take the "
                          "platform down) or 'thread' (in the platform, for debugging with breakpoints)",
                          default="process")
    processor_timeout: float = _key("a processor call unanswered this long (s) gets its process killed and restarted",
                                    minimum=0.5, maximum=600, default=5.0)
    processor_call_timeout: float = _key("operator calls into the processor (F-keys, target selection) fail after "
                                         "this long (s)", minimum=0.05, maximum=60, default=1.0)
    processor_memory_mb: float = _key("cap on the processor process's address space, MB (RLIMIT_AS; 0 = no cap)",
                                      minimum=0, maximum=1e6, default=0)
    safety: SafetyConfig = field(default_factory=SafetyConfig)
    envelope: EnvelopeConfig = field(default_factory=EnvelopeConfig)
    recording: RecordingConfig = field(default_factory=RecordingConfig)
    web: WebConfig = field(default_factory=WebConfig)
    sim: SimConfig = field(default_factory=SimConfig)
    camera: CameraConfig = field(default_factory=CameraConfig)


class Isolation(StrEnum):
    """Where the processor runs (``isolation``): its own process, or a thread of the platform's."""

    PROCESS = "process"
    THREAD = "thread"


ISOLATION_MODES = tuple(Isolation)
"""Values of ``isolation``."""

SECTIONS = {"safety": SafetyConfig, "envelope": EnvelopeConfig, "recording": RecordingConfig, "web": WebConfig,
            "sim": SimConfig, "camera": CameraConfig}
"""TOML table name -> the dataclass its keys go to."""
