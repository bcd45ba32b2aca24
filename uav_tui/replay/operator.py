"""The operator's commands to the processor (F1-F4, ROI) and to the lock on a track (``lock N``, ``unlock``),
replayed at their recorded times."""

from __future__ import annotations

import asyncio
import bisect
import contextlib
import csv
import logging
import math
from collections.abc import Awaitable, Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from uav_tui.errors import KNOWN_ERRORS
from uav_tui.flight.commands import VEHICLE_COMMANDS, Command, parse
from uav_tui.status import CoreState

logger = logging.getLogger(__name__)

PROCESSOR_WORDS = frozenset({"f", "roi"})
"""Commands that reach the processor (``customize_processing``, ``catch_cmd``); the vehicle's are not replayed."""

LOCK_WORDS = frozenset({"lock", "unlock"})
"""Commands to the operator's lock on a track; a vehicle command that released the lock is replayed as ``unlock``."""

COMMAND_TIMEOUT_S = 5.0


@dataclass(frozen=True, slots=True)
class FrameRow:
    """What the replay needs of one frames.csv row."""

    t_mono_ns: int
    """Capture."""
    t_start_ns: int
    t_end_ns: int
    lock_track: int | None
    """The track the lock was on once it steered the frame (None: no lock, or a run recorded before the column)."""


def recorded_commands(run_dir: Path) -> list[tuple[int, Command]]:
    """Each processor and lock command the operator gave in a recorded run, oldest first, with when it is due.

    A processor command is due at the capture time of the first frame the processor started after it took the
    command: a processor takes commands between frames, and with the newest frame winning that frame may have
    been captured before the command was given. The command's outcome row in events.csv is stamped
    when the processor took it (its ``command`` column names the command). Runs recorded before that
    column existed have only the time the command was given, a frame early when the processor started
    one in between; commands the processor failed or did not answer are in them too. (Without a
    frames.csv: at the stamp itself.) A lock command is due at the frame the lock first acted on after it
    (:func:`_lock_due`).
    """
    commands = []
    frames = list(_frame_rows(run_dir / "frames.csv"))
    starts = sorted((frame.t_start_ns, frame.t_mono_ns) for frame in frames)
    floor = 0
    events_csv = run_dir / "events.csv"
    if events_csv.is_file():
        with open(events_csv, newline="") as handle:
            rows = csv.DictReader(handle)
            stamped = "command" in (rows.fieldnames or ())
            for row in rows:
                if row.get("kind") != "command" or row.get("level") != "info" or not row.get("t_mono_ns"):
                    continue
                outcome = stamped and bool(row.get("command"))
                try:
                    command = parse((row["command"] if outcome else row.get("message")) or "")
                except KNOWN_ERRORS:
                    continue  # an outcome ("F1 sent to the processor") in a run without the column
                if command is None:
                    continue
                taken = int(row["t_mono_ns"])
                if command.word in PROCESSOR_WORDS and (outcome or not stamped):
                    first = bisect.bisect_right(starts, (taken, math.inf))
                    commands.append((starts[first][1] if first < len(starts) else taken, command))
                elif not outcome and (command.word in LOCK_WORDS or command.word in VEHICLE_COMMANDS):
                    due = _lock_due(frames, floor, taken, command)
                    if due is not None:
                        floor = due + 1
                        at = frames[due].t_mono_ns if due < len(frames) else taken
                        commands.append((at, command if command.word in LOCK_WORDS else Command("unlock")))
    commands.sort(key=lambda item: item[0])
    return commands


def _lock_due(frames: list[FrameRow], floor: int, taken: int, command: Command) -> int | None:
    """The frames.csv row ``command``, given at ``taken`` (the lock acts at once, on the loop), first acted on:
    None for a vehicle command that released no lock.

    The rows are in the order the loop handled the frames, each after its processing ended: every frame that ended
    after ``taken`` was handled after the command, and so may the last few before it (their results on their way).
    Of those, the one where the lock first became what the command made it (``lock N``: on track N; ``unlock`` or a
    vehicle command: none) is the row. A run recorded before the ``lock_track`` column, or a ``lock`` that failed,
    has no such row: the first frame that ended after it (None for a vehicle command). ``floor``: the row after the
    previous lock command's.
    """
    after = next((i for i in range(floor, len(frames)) if frames[i].t_end_ns > taken), len(frames))
    wanted = command.args[0] if command.word == "lock" else None
    for i in range(min(after, len(frames) - 1), max(floor, 1) - 1, -1):
        if frames[i].lock_track == wanted and frames[i - 1].lock_track != wanted:
            return i
    return after if command.word in LOCK_WORDS else None


def _frame_rows(frames_csv: Path) -> Iterator[FrameRow]:
    """The frames the processor took, in the order the loop handled them (frames.csv's)."""
    if frames_csv.is_file():
        with open(frames_csv, newline="") as handle:
            for row in csv.DictReader(handle):
                with contextlib.suppress(KeyError, TypeError, ValueError):
                    lock = row.get("lock_track") or None
                    yield FrameRow(int(row["t_mono_ns"]), int(row["t_start_ns"]), int(row.get("t_end_ns") or 0),
                                   None if lock is None else int(lock))


class CommandReplay:
    """Gives the replayed core each recorded command before the frame it is due at (:func:`recorded_commands`).

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
