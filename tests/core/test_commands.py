"""The one command vocabulary shared by keys, scripts and the web page."""

from __future__ import annotations

from pathlib import Path

import pytest

from uav_tui.commands import COMMANDS, Command, parse
from uav_tui.errors import CommandError
from uav_tui.headless import load_script


@pytest.mark.parametrize(("line", "expected"), [
    ("arm", Command("arm")),
    ("takeoff 5", Command("takeoff", (5.0,))),
    ("takeoff", Command("takeoff")),
    ("  LAND  ", Command("land")),
    ("orbit 10 2.5", Command("orbit", (10.0, 2.5))),
    ("vector 0.5 -0.2 2", Command("vector", (0.5, -0.2, 2.0))),
    ("autonomy on", Command("autonomy", ("on",))),
    ("f 2", Command("f", (2,))),
    ("roi 100 80 60 40", Command("roi", (100, 80, 60, 40))),
    ("wait 10", Command("wait", (10.0,))),
    ("source file:my flight.mp4", Command("source", ("file:my flight.mp4",))),
    ("hold # stop here", Command("hold")),
], ids=lambda v: str(v) if isinstance(v, str) else "")
def test_parse(line: str, expected: Command) -> None:
    assert parse(line) == expected


@pytest.mark.parametrize("line", ["", "   ", "# a comment"])
def test_blank_lines_and_comments(line: str) -> None:
    assert parse(line) is None


@pytest.mark.parametrize(("line", "message"), [
    ("fly", "unknown command 'fly'"),
    ("f 5", "usage: f N"),
    ("takeoff high", "usage: takeoff"),
    ("vector nan 0 1", "usage: vector"),
    ("vector 1 0 0", "usage: vector"),
    ("vector 1 0", "wrong number of arguments"),
    ("roi 1 2 3", "wrong number of arguments"),
    ("roi -1 2 3 4", "usage: roi"),
    ("autonomy maybe", "usage: autonomy"),
    ("arm now", "wrong number of arguments"),
], ids=lambda v: v)
def test_errors_show_the_usage(line: str, message: str) -> None:
    with pytest.raises(CommandError, match=message):
        parse(line)


def test_every_command_has_usage_and_help() -> None:
    for word, spec in COMMANDS.items():
        assert spec.usage.split()[0] == word and spec.help


def test_script_is_checked_whole_before_running(tmp_path: Path) -> None:
    script = tmp_path / "flight.txt"
    script.write_text("arm\ntakeoff 5\n# hover\nwait 2\nfly home\nland\nf 9\n")
    with pytest.raises(CommandError) as info:
        load_script(script)
    assert f"{script}:5" in str(info.value) and f"{script}:7" in str(info.value)
    script.write_text("arm\ntakeoff 5\n\nwait 2\nland\n")
    assert [n for n, _ in load_script(script)] == [1, 2, 4, 5]
