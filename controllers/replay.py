"""``replay:RUN[?speed=1|4|max]`` — the vehicle of a recorded run, served from its ``telemetry.csv``.

Every recorded telemetry row is handed to the platform at its recorded time (see
:mod:`controllers.replay_timeline`) with its recorded receive stamps, so ``tmMgr.snapshot()``, the
telemetry panel and the recorder see the vehicle exactly as it was. The recorded vehicle cannot be
commanded: vehicle commands raise :class:`NotSupported`, and vectors are never sent anywhere.
With ``speed=max`` the same run's ``run:`` camera drives the timeline; without it nothing moves.
"""

from __future__ import annotations

import csv
import logging
import math
from collections.abc import AsyncIterator
from dataclasses import fields
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs

from controllers.base import Telemetry
from controllers.errors import ConnectError, NotSupported
from controllers.replay_timeline import ReplayTimeline, parse_speed
from controllers.vector_end import VectorEnd

logger = logging.getLogger(__name__)

SCHEME = "replay:"

_TYPES: dict[str, type] = {f.name: next(t for t in (bool, int, float, str) if t.__name__ in str(f.type))
                            for f in fields(Telemetry)}
"""Telemetry field -> the type its CSV text converts to."""
_CLEARED = frozenset({"rangefinder_m", "terrain_height_m"})
"""Fields whose empty cell after a value is news (a rangefinder out of its range, terrain unknown): replayed as
None."""


def parse_address(address: str) -> tuple[Path, float | None]:
    """``replay:PATH[?speed=S]`` -> (run folder, speed or None for ``max``). Raises ConnectError."""
    body = address.strip()[len(SCHEME):]
    path_text, _, query = body.partition("?")
    options = {key: values[-1] for key, values in parse_qs(query, keep_blank_values=True).items()}
    unknown = set(options) - {"speed"}
    if unknown or not path_text:
        problem = f"; unknown option {', '.join(sorted(unknown))}" if unknown else ""
        raise ConnectError(f"{address!r}: expected replay:RUN_FOLDER[?speed=1|4|max] (e.g. replay:runs/"
                           f"2026-05-01T10-00-00Z?speed=max){problem}")
    try:
        speed = parse_speed(options.get("speed"))
    except ValueError as exc:
        raise ConnectError(f"{address!r}: {exc}") from None
    return Path(path_text).expanduser(), speed


def read_telemetry(path: Path) -> list[dict[str, Any]]:
    """The rows of a ``telemetry.csv`` as typed updates (empty cells left out but :data:`_CLEARED`'s), oldest first.

    A run recorded without a vehicle (``--fc none``) has no such file: it has no rows.
    """
    rows: list[dict[str, Any]] = []
    if not path.is_file():
        return rows
    with open(path, newline="") as handle:
        for row in csv.DictReader(handle):
            update = {name: _typed(name, text) if text else None for name, text in row.items()
                      if name in _TYPES and (text or name in _CLEARED)}
            if update.get("t_mono_ns"):
                rows.append(update)
    rows.sort(key=lambda update: update["t_mono_ns"])
    return rows


def first_frame_ns(run_dir: Path) -> int | None:
    """Capture time of the run's first processed frame (``frames.csv``), None when it has none.

    Raises:
        ConnectError: that time is not a whole number (names the file and the line).
    """
    path = run_dir / "frames.csv"
    try:
        with open(path, newline="") as handle:
            row = next(csv.DictReader(handle), None)
    except OSError:
        return None
    text = row.get("t_mono_ns") if row else None
    if not text:
        return None
    try:
        return int(text)
    except ValueError:
        raise ConnectError(f"{path} line 2: t_mono_ns {text[:40]!r} is not a whole number (the file is damaged): "
                           "mend or delete that row, then replay again") from None


def _typed(name: str, text: str) -> Any:
    kind = _TYPES[name]
    if kind is bool:
        return text == "True"
    if kind is int:
        return int(float(text))
    return kind(text)


class ReplayController:
    """The recorded vehicle of ``run_dir``; ``timeline`` is shared with the ``run:`` camera of the same run."""

    def __init__(self, run_dir: Path, speed: float | None) -> None:
        self.run_dir = run_dir
        self.description = f"replay of {run_dir}"
        self.samples = read_telemetry(run_dir / "telemetry.csv")
        starts = [t for t in (self.samples[0]["t_mono_ns"] if self.samples else None, first_frame_ns(run_dir)) if t]
        self.timeline = ReplayTimeline(min(starts, default=0), speed)
        self.applied = 0
        """Recorded telemetry rows handed to the platform so far."""
        self._heartbeat_age: float | None = None

    @classmethod
    def open(cls, address: str) -> ReplayController:
        """Read the run named by ``replay:RUN[?speed=...]``; raises ConnectError saying what is wrong."""
        run_dir, speed = parse_address(address)
        if not (run_dir / "run.json").is_file():
            raise ConnectError(f"{run_dir} is not a recorded run (no run.json); `uav-tui runs` lists them")
        try:
            return cls(run_dir, speed)
        except (OSError, ValueError, KeyError) as exc:
            raise ConnectError(f"{run_dir / 'telemetry.csv'}: cannot be read ({exc})") from None

    async def connect(self, system_address: str) -> None:
        """Nothing to connect: the run was read by :meth:`open`."""

    async def close(self) -> None:
        self.timeline.exhausted()

    async def telemetry(self) -> AsyncIterator[dict[str, Any]]:
        """Every recorded row at its recorded time, with its recorded receive stamps."""
        try:
            for sample in self.samples:
                await self.timeline.reach(sample["t_mono_ns"])
                self._heartbeat_age = sample.get("heartbeat_age_s")
                self.applied += 1
                yield sample
        finally:
            self.timeline.exhausted()

    def heartbeat_age_s(self) -> float:
        """The heartbeat age recorded with the newest replayed row (inf before the first)."""
        age = self._heartbeat_age
        return math.inf if age is None else age

    @property
    def vector_active(self) -> bool:
        return False

    @property
    def last_vector_end(self) -> VectorEnd:
        return VectorEnd()

    async def set_fly_vector(self, vx: float, vy: float, t: float, *, yield_to_others: bool = False) -> None:
        raise self._refuse("vector")

    async def arm(self) -> None:
        raise self._refuse("arm")

    async def disarm(self) -> None:
        raise self._refuse("disarm")

    async def takeoff(self, altitude_m: float | None = None) -> None:
        raise self._refuse("takeoff")

    async def land(self) -> None:
        raise self._refuse("land")

    async def do_orbit(self, radius_m: float, velocity_ms: float) -> None:
        raise self._refuse("orbit")

    async def return_to_home(self) -> None:
        raise self._refuse("rtl")

    async def hold(self) -> None:
        """Nothing to hold: the recorded vehicle is not flying now, and nothing was ever sent to it."""

    def _refuse(self, command: str) -> NotSupported:
        return NotSupported(f"{command}: this is a replay of {self.run_dir.name}; the recorded vehicle "
                            "cannot be commanded")

