"""Configuration: one TOML file (``uav.toml``), every key overridable by a CLI flag.

Search order for the file: ``--config PATH``, ``$UAV_TUI_CONFIG``, ``./uav.toml``,
``$XDG_CONFIG_HOME/uav-tui/uav.toml`` (``~/.config/uav-tui/uav.toml``); the first that exists wins,
none is fine. Keys are unique across sections, so each has one flag: ``max_speed`` -> ``--max-speed``.
"""

from __future__ import annotations

import argparse
import difflib
import math
import os
import tomllib
from collections.abc import Callable
from dataclasses import MISSING, dataclass, field, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from controllers.sim.geo import Home, parse_wind
from processors.frame_telemetry import DEFAULT_SAVE_MAX_HZ
from uav_tui.errors import ConfigError
from uav_tui.output.text import describe
from uav_tui.token_strength import GENERATE_TOKEN, MIN_TOKEN_BITS, token_problem

if TYPE_CHECKING:
    from sources.camera_model import CameraModel


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
                                         "COM_OBL_RC_ACT, GUID_TIMEOUT) when it would fly a dead platform's last "
                                         "command longer than max_t + 0.5 s; off: refuse autonomy instead",
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


@dataclass(frozen=True)
class WebConfig:
    """The optional WebRTC side page."""

    web: bool = _key("serve the WebRTC page", default=False)
    web_host: str = _key("address the page binds to", default="0.0.0.0")
    web_port: int = _key("port of the page", minimum=1, maximum=65535, default=8080)
    web_token: str = _key(f"access token with at least {MIN_TOKEN_BITS} bits of entropy (make one: {GENERATE_TOKEN}); "
                          "empty = a random one per start", default="")
    web_origins: str = _key("other page origins allowed to send commands, comma-separated, e.g. "
                            "https://gcs.local:8443 (the page's own origin is always allowed)", default="")
    web_width: int = _key("width of the streamed video, px", minimum=64, maximum=4096, default=640)
    web_fps: float = _key("frame rate of the streamed video", minimum=1, maximum=60, default=15)
    camera_mavlink: str = _key("MAVLink camera endpoint for ground-station click-to-track, e.g. "
                               "udpin:0.0.0.0:14580 (empty = off)", default="")


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

    def vehicle(self) -> dict[str, Any]:
        """The arguments of :class:`controllers.sim.launcher.SimVehicle` these settings give."""
        return {"home": _home(self.home), "wind": parse_wind(self.wind), "seed": self.seed, "noise": self.noise}


def _calibration_file(path: str) -> None:
    if path.strip():
        from sources.calibration import read_calibration  # OpenCV: only when a file is configured

        read_calibration(path)


def _mount(mount: str, offset: str = "") -> Any:
    from sources.camera_model import Mount

    return Mount.parse(mount, offset)


@dataclass(frozen=True)
class CameraConfig:
    """The camera model of a source that does not state its own (``sim:`` and ``run:`` do): file, or field of view."""

    camera_calibration: str = _key("OpenCV calibration file (uav-tui calibrate writes one); empty: camera_hfov",
                                   default="", parse=_calibration_file, metavar="FILE")
    camera_hfov: float = _key("the camera's horizontal field of view, degrees, without a calibration file "
                              "(0 = unknown: no camera model)", minimum=0, maximum=170, default=0.0)
    camera_mount: str = _key("how the camera is mounted: down, forward, or its tilt below the nose in degrees",
                             default="down", parse=_mount, metavar="down|forward|DEG")
    camera_offset: str = _key("where the camera is from the vehicle's centre: forward, right, down in metres",
                              default="0,0,0", parse=lambda text: _mount("down", text), metavar="F,R,D")

    def model(self, width: int, height: int) -> CameraModel | None:
        """The configured model for frames of ``width`` x ``height``; None when neither file nor hfov is given."""
        from sources.calibration import load_model
        from sources.camera_model import CameraModel

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
    recording: RecordingConfig = field(default_factory=RecordingConfig)
    web: WebConfig = field(default_factory=WebConfig)
    sim: SimConfig = field(default_factory=SimConfig)
    camera: CameraConfig = field(default_factory=CameraConfig)


ISOLATION_MODES = ("process", "thread")
"""Values of ``isolation``."""

SECTIONS = {"safety": SafetyConfig, "recording": RecordingConfig, "web": WebConfig, "sim": SimConfig,
            "camera": CameraConfig}
"""TOML table name -> the dataclass its keys go to."""

_FLAG_GROUPS = {Config: "camera, processor, flight controller (top of uav.toml)", SafetyConfig: "safety ([safety])",
                RecordingConfig: "recording ([recording])", WebConfig: "web page ([web])",
                SimConfig: "built-in simulated vehicle, --fc sim ([sim])",
                CameraConfig: "camera model, for sources that do not state one ([camera])"}
"""``--help`` group titles: what the flags set and where the same keys go in ``uav.toml``."""

_TOP_LEVEL = tuple(f.name for f in fields(Config) if f.name not in SECTIONS)
_ALL_KEYS = (*_TOP_LEVEL, *(f.name for cls in SECTIONS.values() for f in fields(cls)))


def default_config_paths() -> list[Path]:
    """Where ``uav.toml`` is looked for, in order, when ``--config`` is not given."""
    paths = [Path(p) for p in [os.environ.get("UAV_TUI_CONFIG")] if p]
    xdg = Path(os.environ.get("XDG_CONFIG_HOME") or Path.home() / ".config")
    return [*paths, Path("uav.toml"), xdg / "uav-tui" / "uav.toml"]


def find_config_file(explicit: str | None) -> Path | None:
    """The file to load: ``explicit`` (must exist) or the first default path that exists."""
    if explicit:
        path = Path(explicit).expanduser()
        if not path.is_file():
            raise ConfigError(f"config file {path} does not exist", key="config")
        return path
    return next((p for p in default_config_paths() if p.is_file()), None)


def load_config(path: Path | None, overrides: dict[str, Any] | None = None) -> Config:
    """Read ``path`` (None: defaults only), then apply ``overrides`` (flat key -> value, from the CLI)."""
    data: dict[str, Any] = {}
    if path is not None:
        try:
            data = tomllib.loads(path.read_text(encoding="utf-8"))
        except tomllib.TOMLDecodeError as exc:
            raise ConfigError(f"{path}: not valid TOML: {exc}", key="config") from None
        except UnicodeDecodeError as exc:
            raise ConfigError(f"{path}: not UTF-8 text (byte {exc.start}); save it as UTF-8", key="config") from None
        except OSError as exc:
            raise ConfigError(f"cannot read config file {path}: {exc.strerror or exc}", key="config") from None
    where = str(path) if path else "configuration"
    top: dict[str, Any] = {}
    sections: dict[str, dict[str, Any]] = {name: {} for name in SECTIONS}
    for key, value in data.items():
        if key in SECTIONS:
            if not isinstance(value, dict):
                raise ConfigError(f"{where}: [{key}] must be a table", key=key)
            for sub, sub_value in value.items():
                sections[key][sub] = _check(SECTIONS[key], sub, sub_value, f"{key}.{sub}", where)
        else:
            top[key] = _check(Config, key, value, key, where)
    for key, value in (overrides or {}).items():
        section = section_of(key)
        target = top if section is None else sections[section]
        if key == "processor_args":
            target[key] = {**top.get(key, {}), **value}
        else:
            target[key] = _check(Config if section is None else SECTIONS[section], key, value, f"--{_flag(key)}",
                                 "command line")
    config = Config(**top, **{name: cls(**sections[name]) for name, cls in SECTIONS.items()})
    _check_sim_settings(config, where)
    _check_camera_settings(config.camera, where)
    return config


def _check_camera_settings(camera: CameraConfig, where: str) -> None:
    """A mounting without a model to mount would be silently ignored: say so."""
    if camera.camera_calibration.strip() or camera.camera_hfov > 0:
        return
    for f in fields(CameraConfig):
        if f.name in ("camera_mount", "camera_offset") and getattr(camera, f.name) != f.default:
            raise ConfigError(f"{where}: {f.name} places the configured camera model, but there is none: set "
                              "camera_calibration or camera_hfov too (a sim: camera is placed by its URI, e.g. "
                              "sim:?mount=forward&tilt=30)", key=f.name)


def _check_sim_settings(config: Config, where: str) -> None:
    """Simulated-vehicle settings with another flight controller would be silently ignored: say so."""
    if config.fc.strip().lower() == "sim":
        return
    for f in fields(SimConfig):
        if getattr(config.sim, f.name) != f.default:
            raise ConfigError(f"{where}: {f.name} sets up the built-in simulated vehicle, but fc is {config.fc!r}: "
                              f"use it with --fc sim (or drop --{_flag(f.name)} / sim.{f.name})", key=f.name)


def section_of(key: str) -> str | None:
    """The section a flat key lives in (None for top-level keys)."""
    if key in _TOP_LEVEL:
        return None
    for name, cls in SECTIONS.items():
        if key in {f.name for f in fields(cls)}:
            return name
    raise ConfigError(f"unknown configuration key {key!r}", key=key)


def add_config_flags(parser: argparse.ArgumentParser) -> None:
    """One flag per key (``--max-speed``, ``--no-record`` ...), all defaulting to 'not given'."""
    for cls in (Config, *SECTIONS.values()):
        group = parser.add_argument_group(_FLAG_GROUPS[cls])
        for f in fields(cls):
            if cls is Config and f.name in SECTIONS:
                continue
            if f.name == "processor_args":
                group.add_argument("--processor-arg", dest="processor_args", action="append", default=None,
                                   metavar="KEY=VALUE", help="processor constructor argument (TOML value), repeatable")
            elif f.type == "bool":
                group.add_argument(f"--{_flag(f.name)}", action=argparse.BooleanOptionalAction, default=None,
                                   help=f.metadata["help"])
            else:
                group.add_argument(f"--{_flag(f.name)}", default=None, metavar=f.metadata["metavar"] or f.type.upper(),
                                   help=f"{f.metadata['help']} (default: {f.default})")


def overrides_from_args(args: argparse.Namespace) -> dict[str, Any]:
    """The config keys the command line set, converted to their types (errors name the flag)."""
    result: dict[str, Any] = {}
    for cls in (Config, *SECTIONS.values()):
        for f in fields(cls):
            value = getattr(args, f.name, None)
            if value is None or cls is Config and f.name in SECTIONS:
                continue
            if f.name == "processor_args":
                result[f.name] = parse_processor_args(value)
            else:
                result[f.name] = _convert_flag(str(f.type), value, f.name)  # annotations are strings here
    return result


def with_overrides(config: Config, **changes: Any) -> Config:
    """A copy of ``config`` with flat keys changed (validated like the CLI)."""
    sections: dict[str, dict[str, Any]] = {name: {} for name in SECTIONS}
    top: dict[str, Any] = {}
    for key, value in changes.items():
        section = section_of(key)
        cls = Config if section is None else SECTIONS[section]
        (top if section is None else sections[section])[key] = _check(cls, key, value, key, "override")
    return replace(config, **top, **{n: replace(getattr(config, n), **v) for n, v in sections.items() if v})


_PLAIN_TYPES: dict[str, type[Any] | tuple[type[Any], ...]] = {"bool": bool, "int": int, "float": (int, float),
                                                              "str": str}


def _check(cls: type, key: str, value: Any, name: str, where: str) -> Any:
    known = {f.name: f for f in fields(cls) if cls is not Config or f.name not in SECTIONS}
    f = known.get(key)
    if f is None:
        if key in _ALL_KEYS:
            raise ConfigError(f"{where}: {name!r} belongs {_place_of(key)}", key=name)
        close = difflib.get_close_matches(key, known, n=1) or difflib.get_close_matches(key, _ALL_KEYS, n=1)
        elsewhere = f" ({_place_of(close[0])})" if close and close[0] not in known else ""
        hint = f"; did you mean {close[0]!r}{elsewhere}?" if close else f"; known keys: {', '.join(known)}"
        raise ConfigError(f"{where}: unknown key {name!r}{hint}", key=name)
    kind = str(f.type)  # the annotation as written (``from __future__ import annotations``)
    expected = _PLAIN_TYPES.get(kind, dict)
    if isinstance(value, bool) and kind != "bool" or not isinstance(value, expected):
        raise ConfigError(f"{where}: {name} must be {kind.split('[')[0]}, got {describe(value)}", key=name)
    if kind == "float":
        value = float(value)
        if not math.isfinite(value):
            raise ConfigError(f"{where}: {name} must be a finite number, got {describe(value)}", key=name)
    low, high = f.metadata.get("min"), f.metadata.get("max")
    if low is not None and not low <= value <= high:
        raise ConfigError(f"{where}: {name} = {value!r} is out of range [{low}, {high}]", key=name)
    if (parse := f.metadata.get("parse")) is not None:
        try:
            parse(value)
        except ValueError as exc:
            raise ConfigError(f"{where}: {name}: {exc}", key=name) from None
    if kind == "str" and key in ("source", "processor", "fc") and not value.strip():
        raise ConfigError(f"{where}: {name} must not be empty", key=name)
    if key == "web_token" and value and (problem := token_problem(value)):
        raise ConfigError(f"{where}: {name} {problem}", key=name)
    if key == "isolation" and value not in ISOLATION_MODES:
        raise ConfigError(f"{where}: {name} must be one of {', '.join(ISOLATION_MODES)}, got {value!r}", key=name)
    return value


def _place_of(key: str) -> str:
    """Where a known key goes in uav.toml, as said in an error."""
    section = section_of(key)
    return f"under [{section}]" if section else "at the top of the file, before any [section]"


def _convert_flag(type_name: str, text: Any, key: str) -> Any:
    if type_name == "bool" or not isinstance(text, str):
        return text
    try:
        return {"int": int, "float": float}.get(type_name, str)(text)
    except ValueError:
        raise ConfigError(f"--{_flag(key)} must be {type_name}, got {describe(text)}", key=key) from None


def parse_processor_args(items: list[str]) -> dict[str, Any]:
    """``["gain=0.8", "mode=paper"]`` -> keyword arguments: values are TOML literals, bare words strings."""
    result = {}
    for item in items:
        key, sep, raw = item.partition("=")
        if not sep or not key.strip():
            raise ConfigError(f"--processor-arg {describe(item)}: expected KEY=VALUE", key="processor_args")
        try:
            result[key.strip()] = tomllib.loads(f"v = {raw}")["v"]
        except tomllib.TOMLDecodeError:
            result[key.strip()] = raw  # a bare word is a string
    return result


def _flag(key: str) -> str:
    return key.replace("_", "-")
