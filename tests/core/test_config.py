"""Configuration: TOML file, search order, CLI overrides, errors that name the key."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from uav_tui.config import (
    Config,
    add_config_flags,
    find_config_file,
    load_config,
    overrides_from_args,
    with_overrides,
)
from uav_tui.errors import ConfigError

FULL = """
source = "file:flight.mp4"
processor = "csrt"
fc = "serial:///dev/ttyAMA0:57600"

[safety]
max_speed = 0.5
max_t = 1.5

[processor_args]
gain = 0.8

[recording]
runs_dir = "/data/runs"
"""


def cli(*argv: str) -> dict:
    parser = argparse.ArgumentParser()
    add_config_flags(parser)
    return overrides_from_args(parser.parse_args(list(argv)))


def test_each_level_is_one_line(tmp_path: Path) -> None:
    path = tmp_path / "uav.toml"
    path.write_text(FULL)
    config = load_config(path)
    assert (config.source, config.processor, config.fc) == ("file:flight.mp4", "csrt", "serial:///dev/ttyAMA0:57600")
    assert (config.safety.max_speed, config.safety.max_t) == (0.5, 1.5)
    assert config.processor_args == {"gain": 0.8}
    assert config.recording.runs_dir == "/data/runs"


def test_defaults_need_no_file() -> None:
    assert load_config(None) == Config()


def test_cli_overrides_win(tmp_path: Path) -> None:
    path = tmp_path / "uav.toml"
    path.write_text(FULL)
    config = load_config(path, cli("--source", "synthetic:", "--max-speed", "0.3", "--no-record",
                                   "--processor-arg", "gain=1.5", "--processor-arg", "mode=paper"))
    assert config.source == "synthetic:"
    assert config.safety.max_speed == 0.3 and config.safety.max_t == 1.5
    assert config.recording.record is False
    assert config.processor_args == {"gain": 1.5, "mode": "paper"}


@pytest.mark.parametrize(("text", "key"), [
    ("sourse = 'x:'", "sourse"),
    ("[safety]\nmax_sped = 1", "safety.max_sped"),
    ("[safety]\nmax_speed = 'fast'", "safety.max_speed"),
    ("[safety]\nmax_speed = 100.0", "safety.max_speed"),
    ("[safety]\nmax_t = nan", "safety.max_t"),
    ("[web]\nweb_port = 70000", "web.web_port"),
    ("[recording]\nrecord = 1", "recording.record"),
    ("fc = ''", "fc"),
    ("safety = 3", "safety"),
], ids=["unknown-top", "unknown-in-section", "wrong-type", "out-of-range", "nan", "port", "bool-as-int", "empty",
        "section-not-table"])
def test_bad_keys_and_values_name_the_key(tmp_path: Path, text: str, key: str) -> None:
    path = tmp_path / "uav.toml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert info.value.key == key
    assert key.split(".")[-1] in str(info.value)


def test_typo_gets_a_suggestion(tmp_path: Path) -> None:
    path = tmp_path / "uav.toml"
    path.write_text("[safety]\nmax_sped = 1")
    with pytest.raises(ConfigError, match="did you mean 'max_speed'"):
        load_config(path)


def test_invalid_toml_is_reported(tmp_path: Path) -> None:
    path = tmp_path / "uav.toml"
    path.write_text("source = ")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_config(path)


def test_bad_flag_value_names_the_flag() -> None:
    with pytest.raises(ConfigError, match="--max-speed") as info:
        load_config(None, cli("--max-speed", "fast"))
    assert info.value.key == "max_speed"


def test_search_order(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "xdg"))
    monkeypatch.delenv("UAV_TUI_CONFIG", raising=False)
    assert find_config_file(None) is None
    user = tmp_path / "xdg" / "uav-tui" / "uav.toml"
    user.parent.mkdir(parents=True)
    user.write_text("")
    assert find_config_file(None) == user
    local = tmp_path / "uav.toml"
    local.write_text("")
    assert find_config_file(None) == Path("uav.toml")
    env = tmp_path / "env.toml"
    env.write_text("")
    monkeypatch.setenv("UAV_TUI_CONFIG", str(env))
    assert find_config_file(None) == env
    assert find_config_file(str(user)) == user
    with pytest.raises(ConfigError, match="does not exist"):
        find_config_file(str(tmp_path / "missing.toml"))


def test_with_overrides_validates() -> None:
    assert with_overrides(Config(), max_t=1.0).safety.max_t == 1.0
    with pytest.raises(ConfigError):
        with_overrides(Config(), max_t=-1.0)
