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

from uav_tui.errors import CommandError


def _finite(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError("not finite")
    return value


def _positive(text: str) -> float:
    value = _finite(text)
    if value <= 0:
        raise ValueError("not > 0")
    return value


def _pixels(text: str) -> int:
    value = int(float(text))
    if value < 0:
        raise ValueError("negative")
    return value


def _button(text: str) -> int:
    value = int(text)
    if not 1 <= value <= 4:
        raise ValueError("not 1..4")
    return value


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


COMMANDS: dict[str, CommandSpec] = {
    "arm": CommandSpec("arm", "arm the motors"),
    "disarm": CommandSpec("disarm", "disarm the motors (refused in the air by the autopilot)"),
    "takeoff": CommandSpec("takeoff [ALT]", "take off to ALT metres (default: takeoff_alt)", (_positive,), 1),
    "land": CommandSpec("land", "land where it is"),
    "rtl": CommandSpec("rtl", "return to launch and land"),
    "hold": CommandSpec("hold", "stop and hold position"),
    "orbit": CommandSpec("orbit R V", "orbit the current position at radius R m and speed V m/s",
                         (_positive, _finite)),
    "vector": CommandSpec("vector VX VY T", "fly body-frame velocity VX (forward) VY (right) m/s for T s",
                          (_finite, _finite, _positive)),
    "autonomy": CommandSpec("autonomy on|off|toggle", "let the processor's vectors fly the vehicle", (_switch,)),
    "f": CommandSpec("f N", "press F1..F4: customize_processing(N)", (_button,)),
    "roi": CommandSpec("roi X Y W H", "select a region in frame pixels: catch_cmd((X, Y, W, H))",
                       (_pixels, _pixels, _pixels, _pixels)),
    "snapshot": CommandSpec("snapshot", "save the current frame into the run"),
    "reload": CommandSpec("reload", "reload the processor from its file, keeping the old one on error"),
    "source": CommandSpec("source URI", "switch the camera to URI without stopping anything else", (str,),
                          rest=True),
    "wait": CommandSpec("wait S", "scripts only: wait S seconds", (_positive,)),
    "quit": CommandSpec("quit", "hold the vehicle if flying, then exit"),
}
"""Every command word. Keys are bound to these in the TUI; scripts and the web page send them as text."""

VEHICLE_COMMANDS = frozenset({"arm", "disarm", "takeoff", "land", "rtl", "hold", "orbit", "vector"})
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
        close = difflib.get_close_matches(word, COMMANDS, n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise CommandError(f"unknown command {word!r}; {hint}commands: {', '.join(COMMANDS)}", key="command")
    try:
        words = [rest.strip()] if spec.rest and rest.strip() else shlex.split(rest)
    except ValueError as exc:
        raise CommandError(f"{text!r}: {exc}; usage: {spec.usage}", key="command") from None
    if not len(spec.args) - spec.optional <= len(words) <= len(spec.args):
        raise CommandError(f"{text!r}: wrong number of arguments; usage: {spec.usage}", key="command")
    try:
        args = tuple(convert(word) for convert, word in zip(spec.args, words, strict=False))
    except ValueError:
        raise CommandError(f"{text!r}: bad argument; usage: {spec.usage}", key="command") from None
    return Command(word, args)


def help_text() -> str:
    """One line per command, for ``--help`` and the TUI."""
    width = max(len(spec.usage) for spec in COMMANDS.values())
    return "\n".join(f"  {spec.usage:<{width}}  {spec.help}" for spec in COMMANDS.values())
