"""The command line's side of the configuration: one flag per key, and the keys the flags set."""

from __future__ import annotations

import argparse
import tomllib
from dataclasses import fields
from typing import Any

from uav_tui.config.settings import (
    SECTIONS,
    CameraConfig,
    Config,
    EnvelopeConfig,
    RecordingConfig,
    SafetyConfig,
    SimConfig,
    WebConfig,
)
from uav_tui.errors import ConfigError
from uav_tui.output.text import describe

_FLAG_GROUPS = {Config: "camera, processor, flight controller (top of uav.toml)", SafetyConfig: "safety ([safety])",
                EnvelopeConfig: "where, how high and how long autonomy may fly ([envelope])",
                RecordingConfig: "recording ([recording])", WebConfig: "web page ([web])",
                SimConfig: "built-in simulated vehicle, --fc sim ([sim])",
                CameraConfig: "camera model, for sources that do not state one ([camera])"}
"""``--help`` group titles: what the flags set and where the same keys go in ``uav.toml``."""


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
                group.add_argument(f"--{flag_name(f.name)}", action=argparse.BooleanOptionalAction, default=None,
                                   help=f.metadata["help"])
            else:
                group.add_argument(f"--{flag_name(f.name)}", default=None,
                                   metavar=f.metadata["metavar"] or f.type.upper(),
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


def _convert_flag(type_name: str, text: Any, key: str) -> Any:
    if type_name == "bool" or not isinstance(text, str):
        return text
    try:
        return {"int": int, "float": float}.get(type_name, str)(text)
    except ValueError:
        raise ConfigError(f"--{flag_name(key)} must be {type_name}, got {describe(text)}", key=key) from None


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


def flag_name(key: str) -> str:
    """The flag of config key ``key``: ``max_speed`` -> ``max-speed`` (``--max-speed``)."""
    return key.replace("_", "-")
