"""Configuration: one TOML file (``uav.toml``), every key overridable by a CLI flag.

- :mod:`~uav_tui.config.settings`: the keys, one frozen dataclass per section (``Config`` and its sections).
- :mod:`~uav_tui.config.loading`: finding and reading the file, the command line's keys over it, each value checked.
- :mod:`~uav_tui.config.flags`: one command-line flag per key, and the keys the flags set.
"""

from __future__ import annotations

from uav_tui.config.flags import add_config_flags, overrides_from_args, parse_processor_args
from uav_tui.config.loading import (
    default_config_paths,
    find_config_file,
    load_config,
    section_of,
    with_overrides,
)
from uav_tui.config.settings import (
    ISOLATION_MODES,
    SECTIONS,
    CameraConfig,
    Config,
    EnvelopeConfig,
    Isolation,
    RecordingConfig,
    SafetyConfig,
    SimConfig,
    WebConfig,
)

__all__ = [
    "ISOLATION_MODES",
    "Isolation",
    "SECTIONS",
    "CameraConfig",
    "Config",
    "EnvelopeConfig",
    "RecordingConfig",
    "SafetyConfig",
    "SimConfig",
    "WebConfig",
    "add_config_flags",
    "default_config_paths",
    "find_config_file",
    "load_config",
    "overrides_from_args",
    "parse_processor_args",
    "section_of",
    "with_overrides",
]
