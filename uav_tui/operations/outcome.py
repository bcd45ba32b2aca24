"""What a command's coroutine is (:data:`Handler`) and what it returns (:class:`Outcome`)."""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import NamedTuple


class Outcome(NamedTuple):
    """What a command did, and when, if that was before it returned."""

    message: str
    t_mono_ns: int | None = None
    """When it took effect (monotonic ns); None: when it returned. A processor call took effect when the
    processor began it: the frames it started after that saw it (a replay gives it before the same frame)."""


Handler = Callable[..., Awaitable[Outcome | str]]
"""One command's coroutine: called with the command's arguments and ``origin=``; returns what happened."""
