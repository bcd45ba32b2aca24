"""The operator's commands to the processor (F1-F4, ROI), replayed at their recorded times."""

from __future__ import annotations

import asyncio
import bisect
import contextlib
import csv
import logging
import math
from collections.abc import Awaitable, Callable
from pathlib import Path

from uav_tui.errors import KNOWN_ERRORS
from uav_tui.flight.commands import Command, parse
from uav_tui.status import CoreState

logger = logging.getLogger(__name__)

PROCESSOR_WORDS = frozenset({"f", "roi"})
"""Commands that reach the processor (``customize_processing``, ``catch_cmd``); the vehicle's are not replayed."""

COMMAND_TIMEOUT_S = 5.0


def recorded_commands(run_dir: Path) -> list[tuple[int, Command]]:
    """Each processor command the operator gave in a recorded run, oldest first, with when it is due.

    It is due at the capture time of the first frame the processor started after it took the command:
    a processor takes commands between frames, and with the newest frame winning that frame may have
    been captured before the command was given. The command's outcome row in events.csv is stamped
    when the processor took it (its ``command`` column names the command). Runs recorded before that
    column existed have only the time the command was given, a frame early when the processor started
    one in between; commands the processor failed or did not answer are in them too. (Without a
    frames.csv: at the stamp itself.)
    """
    commands = []
    starts = _frame_starts(run_dir / "frames.csv")
    events_csv = run_dir / "events.csv"
    if events_csv.is_file():
        with open(events_csv, newline="") as handle:
            rows = csv.DictReader(handle)
            stamped = "command" in (rows.fieldnames or ())
            for row in rows:
                if row.get("kind") != "command" or row.get("level") != "info" or not row.get("t_mono_ns"):
                    continue
                text = row["command"] if stamped else row.get("message")
                try:
                    command = parse(text or "")
                except KNOWN_ERRORS:
                    continue  # an outcome ("F1 sent to the processor") in a run without the column
                if command is not None and command.word in PROCESSOR_WORDS:
                    taken = int(row["t_mono_ns"])
                    first = bisect.bisect_right(starts, (taken, math.inf))
                    commands.append((starts[first][1] if first < len(starts) else taken, command))
    commands.sort(key=lambda item: item[0])
    return commands


def _frame_starts(frames_csv: Path) -> list[tuple[int, int]]:
    """(processing start, capture time) of each frame the processor took, in the order it took them."""
    starts = []
    if frames_csv.is_file():
        with open(frames_csv, newline="") as handle:
            for row in csv.DictReader(handle):
                with contextlib.suppress(KeyError, TypeError, ValueError):
                    starts.append((int(row["t_start_ns"]), int(row["t_mono_ns"])))
    starts.sort()
    return starts


class CommandReplay:
    """Gives the replayed processor each recorded command before the frame it is due at (:func:`recorded_commands`).

    :meth:`before_show` runs on the camera thread (the timeline's ``before_show`` hook) and waits for
    the command to finish, so the processor has it before that frame, in lockstep and paced alike.

    Args:
        execute: runs one command as the operator's (the core's, origin ``replay``).
        state: where the core is in its life: a command waits while it is still starting.
        loop: the core's event loop.
        commands: what :func:`recorded_commands` found.
    """

    def __init__(self, execute: Callable[[Command], Awaitable[object]], state: Callable[[], CoreState],
                 loop: asyncio.AbstractEventLoop, commands: list[tuple[int, Command]]) -> None:
        self.execute = execute
        self.state = state
        self.loop = loop
        self.commands = commands
        self.replayed = 0

    def before_show(self, t_ns: int) -> None:
        while self.replayed < len(self.commands) and self.commands[self.replayed][0] <= t_ns:
            command = self.commands[self.replayed][1]
            self.replayed += 1
            future = asyncio.run_coroutine_threadsafe(self._execute(command), self.loop)
            try:
                future.result(COMMAND_TIMEOUT_S)
            except KNOWN_ERRORS + (TimeoutError,) as exc:  # the core's event log has said why
                logger.info("replayed command %s failed: %s", command, exc)

    async def _execute(self, command: Command) -> None:
        while self.state() is CoreState.NEW:  # the camera can run ahead of the core's start
            await asyncio.sleep(0.01)
        await self.execute(command)
