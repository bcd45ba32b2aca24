"""The one command vocabulary shared by keys, scripts and the web page."""

from __future__ import annotations

import asyncio
from dataclasses import fields
from pathlib import Path
from typing import cast

import pytest

from uav_tui.config import Config, SafetyConfig, load_config, with_overrides
from uav_tui.core import UavCore
from uav_tui.errors import CommandError, ConfigError
from uav_tui.flight.commands import COMMANDS, Command, check_limits, parse
from uav_tui.headless import load_script
from uav_tui.hosting.exception_reports import ProcessorErrors
from uav_tui.operations import Operations, build_operations
from uav_tui.start_parts import Parts


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
    ("lock 3", Command("lock", (3,))),
    ("unlock", Command("unlock")),
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
    ("lock -1", "ID = .-1.: not a track number"),
    ("lock 1.5", "usage: lock ID"),
    ("lock 1000000", "not a track number"),
    ("lock", "wrong number of arguments"),
    ("arm now", "wrong number of arguments"),
], ids=lambda v: v)
def test_errors_show_the_usage(line: str, message: str) -> None:
    with pytest.raises(CommandError, match=message):
        parse(line)


def test_every_command_has_usage_and_help() -> None:
    for word, spec in COMMANDS.items():
        assert spec.usage.split()[0] == word and spec.help


def _unbound() -> Operations:
    """The commands, on no parts: enough to look a word up."""
    nothing = dict.fromkeys((f.name for f in fields(Parts)), None)
    return build_operations(Parts(**{**nothing, "config": Config()}), None, cast(ProcessorErrors, None),
                            asyncio.Event())


def test_every_command_word_has_its_handler() -> None:
    assert set(_unbound().handlers) == set(COMMANDS)


async def test_an_unknown_word_is_refused_by_the_commands_as_parse_refuses_it() -> None:
    with pytest.raises(CommandError) as refused:
        await _unbound().run(Command("takof"), "test")
    with pytest.raises(CommandError) as parsed:
        parse("takof")
    assert str(refused.value) == str(parsed.value) and "did you mean 'takeoff'?" in str(refused.value)


def test_script_is_checked_whole_before_running(tmp_path: Path) -> None:
    script = tmp_path / "flight.txt"
    script.write_text("arm\ntakeoff 5\n# hover\nwait 2\nfly home\nland\nf 9\n")
    with pytest.raises(CommandError) as info:
        load_script(script)
    assert f"{script}:5" in str(info.value) and f"{script}:7" in str(info.value)
    script.write_text("arm\ntakeoff 5\n\nwait 2\nland\n")
    assert [n for n, _ in load_script(script)] == [1, 2, 4, 5]


SAFETY = SafetyConfig()


@pytest.mark.parametrize(("line", "limit"), [
    ("takeoff 10000", "max_altitude"),
    ("orbit 100000 2", "max_orbit_radius"),
    ("orbit 10 1000", "max_orbit_speed"),
    ("orbit 5 -1e9", "max_orbit_speed"),
], ids=lambda v: v)
def test_arguments_beyond_their_limit_are_refused_naming_it(line: str, limit: str) -> None:
    command = parse(line)
    assert command is not None
    with pytest.raises(CommandError, match=f"beyond the limit {limit} = ") as refused:
        check_limits(command, SAFETY)
    assert refused.value.key == limit


@pytest.mark.parametrize("line", ["takeoff 120", "orbit 100 5", "orbit 10 -5", "takeoff", "vector 9 9 9", "f 2"])
def test_arguments_within_their_limits_pass(line: str) -> None:
    command = parse(line)
    assert command is not None
    check_limits(command, SAFETY)


@pytest.mark.parametrize("line", ["roi inf 0 1 1", "roi 1e999 0 1 1", "takeoff inf", "orbit 5 nan", "wait 1e9",
                                  "vector 1e999 0 1"])
def test_non_finite_and_absurd_values_are_refused(line: str) -> None:
    with pytest.raises(CommandError, match="bad argument .*; usage"):
        parse(line)


@pytest.mark.parametrize(("line", "reason"), [
    ("orbit 1e-300 1", "bad argument R = '1e-300': below 1 m, the smallest orbit radius"),
    ("orbit 0.5 1", "bad argument R = '0.5': below 1 m"),
    ("orbit 5 1e-300", "bad argument V = '1e-300': |V| below 0.1 m/s"),
    ("orbit 5 -0", "bad argument V = '-0': |V| below 0.1 m/s"),
    ("orbit 5 nan", "bad argument V = 'nan': not a finite number"),
    ("orbit five 1", "bad argument R = 'five': not a number"),
    ("f 9", "bad argument N = '9': not 1..4"),
    ("takeoff 1e-300", "bad argument ALT = '1e-300': below 1 m, the lowest take-off altitude"),
    ("takeoff 0.5", "bad argument ALT = '0.5': below 1 m"),
], ids=lambda v: v)
def test_a_bad_argument_is_named_with_what_it_must_be(line: str, reason: str) -> None:
    with pytest.raises(CommandError) as refused:
        parse(line)
    assert reason in str(refused.value) and str(refused.value).endswith(f"; usage: {COMMANDS[line.split()[0]].usage}")


async def test_an_orbit_no_autopilot_flies_never_reaches_the_vehicle() -> None:
    settings = {"fc": "sim", "source": "synthetic:?width=160&height=120", "record": False}
    core = UavCore(load_config(None, settings))
    await core.start()
    try:
        await core.execute("arm")
        for line in ("orbit 1e-300 1", "orbit 5 1e-300"):
            with pytest.raises(CommandError, match="bad argument"):
                await core.execute(line)
        assert not [e for e in core.events.recent if "orbit" in e.message]  # nothing was sent, nothing refused
        assert core.telemetry.snapshot().flight_mode != "ORBIT"
    finally:
        await core.stop("test finished")


def test_a_config_may_raise_the_limits_but_not_set_takeoff_alt_above_them() -> None:
    raised = with_overrides(Config(), max_altitude=500).safety
    check_limits(Command("takeoff", (400.0,)), raised)
    with pytest.raises(ConfigError, match="takeoff_alt = 50 is above max_altitude = 30"):
        with_overrides(Config(), max_altitude=30, takeoff_alt=50)


def test_script_limits_are_checked_before_anything_runs(tmp_path: Path) -> None:
    script = tmp_path / "flight.txt"
    script.write_text("arm\ntakeoff 10000\norbit 5 -1e9\nroi inf 0 1 1\nland\n")
    with pytest.raises(CommandError) as info:
        load_script(script, SAFETY)
    lines = str(info.value).splitlines()
    assert [line.split(": ", 1)[0] for line in lines] == [f"{script}:{n}" for n in (2, 3, 4)]
    assert "max_altitude" in lines[0] and "max_orbit_speed" in lines[1] and "bad argument" in lines[2]


async def test_takeoff_beyond_max_altitude_never_reaches_the_vehicle(tmp_path: Path) -> None:
    settings = {"fc": "sim", "source": "synthetic:?width=160&height=120", "record": False}
    core = UavCore(load_config(None, settings))
    await core.start()
    try:
        truth = core.controller.sim.truth()
        await core.execute("arm")
        for line in ("takeoff 10000", "orbit 100000 1000", "orbit 5 -1e9"):
            with pytest.raises(CommandError, match="beyond the limit"):
                await core.execute(line)
        errors = [e.message for e in core.events.recent if e.level == "error" and e.kind == "command"]
        assert len(errors) == 3 and "max_altitude" in errors[0]
        await asyncio.sleep(1.0)  # the simulator's ground truth: still on the ground, not climbing
        state = truth.latest()
        assert -state["d"] < 0.2 and abs(state["vd"]) < 0.1
    finally:
        await core.stop("test finished")
