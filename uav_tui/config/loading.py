"""Reading the configuration: one TOML file (``uav.toml``), then the command line's keys, each value checked.

Search order for the file: ``--config PATH``, ``$UAV_TUI_CONFIG``, ``./uav.toml``,
``$XDG_CONFIG_HOME/uav-tui/uav.toml`` (``~/.config/uav-tui/uav.toml``); the first that exists wins,
none is fine. Keys are unique across sections, so each has one flag: ``max_speed`` -> ``--max-speed``.
"""

from __future__ import annotations

import difflib
import math
import os
import tomllib
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

from uav_tui.config.flags import flag_name
from uav_tui.config.settings import ISOLATION_MODES, SECTIONS, CameraConfig, Config, SimConfig
from uav_tui.errors import ConfigError
from uav_tui.output.text import describe
from uav_tui.token_strength import token_problem

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
    return config_from_data(read_config_data(path), overrides, str(path) if path else "configuration")


def read_config_data(path: Path | None) -> dict[str, Any]:
    """The TOML tables of ``path`` as read, unchecked (None: no file, empty)."""
    if path is None:
        return {}
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML: {exc}", key="config") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: not UTF-8 text (byte {exc.start}); save it as UTF-8", key="config") from None
    except OSError as exc:
        raise ConfigError(f"cannot read config file {path}: {exc.strerror or exc}", key="config") from None


def config_from_data(data: dict[str, Any], overrides: dict[str, Any] | None, where: str) -> Config:
    """The configuration of TOML tables ``data`` (read from ``where``) with ``overrides`` over them, each checked."""
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
            target[key] = _check(Config if section is None else SECTIONS[section], key, value, f"--{flag_name(key)}",
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
                              f"use it with --fc sim (or drop --{flag_name(f.name)} / sim.{f.name})", key=f.name)


def section_of(key: str) -> str | None:
    """The section a flat key lives in (None for top-level keys)."""
    if key in _TOP_LEVEL:
        return None
    for name, cls in SECTIONS.items():
        if key in {f.name for f in fields(cls)}:
            return name
    raise ConfigError(f"unknown configuration key {key!r}", key=key)


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


def _shown(name: str, value: Any) -> str:
    return f"[{name}]" if isinstance(value, dict) else repr(name)


def _suggestion(cls: type, key: str, value: Any, known: list[str]) -> str:
    """``; did you mean ...?`` for an unknown key (a section's name for a table at the top), or what there is."""
    sections = [f"[{name}]" for name in SECTIONS]
    if cls is Config and isinstance(value, dict):
        close = difflib.get_close_matches(key, list(SECTIONS), n=1, cutoff=0.6)
        return f"; did you mean [{close[0]}]?" if close else f"; the sections are {', '.join(sections)}"
    close = difflib.get_close_matches(key, known, n=1) or difflib.get_close_matches(key, _ALL_KEYS, n=1)
    if cls is Config and not close:
        close = [f"[{name}]" for name in difflib.get_close_matches(key, list(SECTIONS), n=1, cutoff=0.6)]
    if close:
        elsewhere = f" ({_place_of(close[0])})" if close[0] not in known and close[0] in _ALL_KEYS else ""
        return f"; did you mean {close[0]!r}{elsewhere}?"
    listed = f"; known keys: {', '.join(known)}"
    return listed + (f"; sections: {', '.join(sections)}" if cls is Config else "")


def _check(cls: type, key: str, value: Any, name: str, where: str) -> Any:
    known = {f.name: f for f in fields(cls) if cls is not Config or f.name not in SECTIONS}
    f = known.get(key)
    if f is None:
        if key in _ALL_KEYS:
            raise ConfigError(f"{where}: {name!r} belongs {_place_of(key)}", key=name)
        raise ConfigError(f"{where}: unknown {'table' if isinstance(value, dict) else 'key'} {_shown(name, value)}"
                          f"{_suggestion(cls, key, value, list(known))}", key=name)
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
