"""Operator commands: the one vocabulary shared by keys, ``--script`` files, the web page and MAVLink.

``parse("takeoff 5")`` -> ``Command("takeoff", (5.0,))``. Blank lines and ``#`` comments parse to None.
"""

from __future__ import annotations

import difflib
import math
import shlex
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from processors.detections import MAX_TRACK_ID
from uav_tui.config import SafetyConfig
from uav_tui.errors import CommandError
from uav_tui.output.text import describe

MAX_WAIT_S = 24 * 3600.0
"""The longest ``wait`` in a script."""

MIN_ORBIT_RADIUS_M = 1.0
"""The smallest ``orbit R``: PX4 flies no smaller orbit (the built-in vehicle refuses one too)."""

MIN_TAKEOFF_ALT_M = 1.0
"""The lowest ``takeoff ALT``: lower is ground effect, not a hover (and ``1e-300`` is no altitude)."""

MIN_ORBIT_SPEED_MS = 0.1
"""The slowest ``orbit R V``, |V| (V < 0 circles the other way): anything slower is no orbit."""

# Argument converters: each returns the value or raises ValueError saying what the value must be.


def _finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ValueError("not a number") from None
    if not math.isfinite(value):
        raise ValueError("not a finite number")
    return value


def _positive(text: str) -> float:
    value = _finite(text)
    if value <= 0:
        raise ValueError("must be > 0")
    return value


def _seconds(text: str) -> float:
    value = _positive(text)
    if value > MAX_WAIT_S:
        raise ValueError(f"longer than {MAX_WAIT_S:g} s")
    return value


def _pixels(text: str) -> int:
    value = int(_finite(text))
    if value < 0:
        raise ValueError("negative")
    return value


def _button(text: str) -> int:
    if text not in ("1", "2", "3", "4"):
        raise ValueError("not 1..4")
    return int(text)


def _takeoff_alt(text: str) -> float:
    value = _finite(text)
    if value < MIN_TAKEOFF_ALT_M:
        raise ValueError(f"below {MIN_TAKEOFF_ALT_M:g} m, the lowest take-off altitude")
    return value


def _orbit_radius(text: str) -> float:
    value = _finite(text)
    if value < MIN_ORBIT_RADIUS_M:
        raise ValueError(f"below {MIN_ORBIT_RADIUS_M:g} m, the smallest orbit radius")
    return value


def _orbit_speed(text: str) -> float:
    value = _finite(text)
    if abs(value) < MIN_ORBIT_SPEED_MS:
        raise ValueError(f"|V| below {MIN_ORBIT_SPEED_MS:g} m/s is no orbit (a negative V circles the other way)")
    return value


def _track(text: str) -> int:
    if not (text.isascii() and text.isdigit()) or int(text) >= MAX_TRACK_ID:
        raise ValueError(f"not a track number (0 to {MAX_TRACK_ID - 1})")
    return int(text)


def _switch(text: str) -> str:
    if text not in ("on", "off", "toggle"):
        raise ValueError("not on/off/toggle")
    return text


@dataclass(frozen=True)
class CommandSpec:
    """How a command word is written and what it does."""

    usage: str
    help: str
    args: tuple[Callable[[str], Any], ...] = ()
    optional: int = 0
    """How many trailing args may be left out."""
    rest: bool = False
    """The single argument takes the rest of the line (a URI with spaces, say)."""
    limits: tuple[str | None, ...] = ()
    """Per argument, the :class:`SafetyConfig` key its magnitude may not exceed (None: no such limit)."""

    @property
    def arg_names(self) -> list[str]:
        """The arguments' names from the usage (``orbit R V`` -> ``['R', 'V']``)."""
        return [name.strip("[]") for name in self.usage.split()[1:]]


COMMANDS: dict[str, CommandSpec] = {
    "arm": CommandSpec("arm", "arm the motors"),
    "disarm": CommandSpec("disarm", "disarm the motors (refused in the air by the autopilot)"),
    "takeoff": CommandSpec("takeoff [ALT]", "take off to ALT metres (default: takeoff_alt)", (_takeoff_alt,), 1,
                           limits=("max_altitude",)),
    "land": CommandSpec("land", "land where it is"),
    "precland": CommandSpec("precland", "land on the landing target the processor sees (precision landing)"),
    "rtl": CommandSpec("rtl", "return to launch and land"),
    "hold": CommandSpec("hold", "stop and hold position"),
    "orbit": CommandSpec("orbit R V", "orbit the current position at radius R m and speed V m/s",
                         (_orbit_radius, _orbit_speed), limits=("max_orbit_radius", "max_orbit_speed")),
    "vector": CommandSpec("vector VX VY T", "fly body-frame velocity VX (forward) VY (right) m/s for T s",
                          (_finite, _finite, _positive)),
    "autonomy": CommandSpec("autonomy on|off|toggle", "let the processor's vectors fly the vehicle", (_switch,)),
    "f": CommandSpec("f N", "press F1..F4: customize_processing(N)", (_button,)),
    "roi": CommandSpec("roi X Y W H", "select a region in frame pixels: catch_cmd((X, Y, W, H))",
                       (_pixels, _pixels, _pixels, _pixels)),
    "lock": CommandSpec("lock ID", "lock on track ID (its #number on the video): it steers the vehicle under autonomy",
                        (_track,)),
    "unlock": CommandSpec("unlock", "release the lock on a track"),
    "snapshot": CommandSpec("snapshot", "save the current frame into the run"),
    "reload": CommandSpec("reload", "reload the processor from its file, keeping the old one on error"),
    "source": CommandSpec("source URI", "switch the camera to URI without stopping anything else", (str,),
                          rest=True),
    "wait": CommandSpec("wait S", "scripts only: wait S seconds", (_seconds,)),
    "quit": CommandSpec("quit", "hold the vehicle if flying, then exit"),
}
"""Every command word. Keys are bound to these in the TUI; scripts and the web page send them as text."""

VEHICLE_COMMANDS = frozenset({"arm", "disarm", "takeoff", "land", "precland", "rtl", "hold", "orbit", "vector"})
"""Commands that need a flight controller and pre-empt autonomy."""


@dataclass(frozen=True)
class Command:
    """A parsed operator command."""

    word: str
    args: tuple[Any, ...] = ()

    def __str__(self) -> str:
        return " ".join([self.word, *(str(a) for a in self.args)])


def parse(line: str) -> Command | None:
    """Parse one command line; None for blank lines and comments, CommandError with the usage otherwise."""
    text = line.split("#", 1)[0].strip()
    if not text:
        return None
    word, _, rest = text.partition(" ")
    word = word.lower()
    spec = COMMANDS.get(word)
    if spec is None:
        raise unknown_command(word)
    try:
        words = [rest.strip()] if spec.rest and rest.strip() else shlex.split(rest)
    except ValueError as exc:
        raise CommandError(f"{describe(text)}: {exc}; usage: {spec.usage}", key="command") from None
    if not len(spec.args) - spec.optional <= len(words) <= len(spec.args):
        raise CommandError(f"{describe(text)}: wrong number of arguments; usage: {spec.usage}", key="command")
    args = []
    for convert, name, value in zip(spec.args, spec.arg_names, words, strict=False):
        try:
            args.append(convert(value))
        except ValueError as exc:
            raise CommandError(f"{describe(text)}: bad argument {name} = {describe(value)}: {exc}; usage: "
                               f"{spec.usage}", key="command") from None
    return Command(word, tuple(args))


def unknown_command(word: str) -> CommandError:
    """The error for a word that is no command: the closest one as a hint, and every command."""
    close = difflib.get_close_matches(word, COMMANDS, n=1)
    hint = f"did you mean {close[0]!r}? " if close else ""
    return CommandError(f"unknown command {describe(word)}; {hint}commands: {', '.join(COMMANDS)}", key="command")


def check_limits(command: Command, safety: SafetyConfig) -> None:
    """Refuse a command whose argument exceeds its configured limit; the message names the limit.

    Raises:
        CommandError: with ``key`` set to the limit's configuration key.
    """
    spec = COMMANDS[command.word]
    for name, key, value in zip(spec.arg_names, spec.limits, command.args, strict=False):
        if not key:
            continue
        limit = getattr(safety, key)
        if limit is not None and abs(value) > limit:
            raise CommandError(f"{command}: {name} = {value:g} is beyond the limit {key} = {limit:g}; raise "
                               f"{key} in the [safety] section of uav.toml (or --{key.replace('_', '-')}) to "
                               "allow it", key=key)


def help_text() -> str:
    """One line per command, for ``--help`` and the TUI."""
    width = max(len(spec.usage) for spec in COMMANDS.values())
    return "\n".join(f"  {spec.usage:<{width}}  {spec.help}" for spec in COMMANDS.values())
