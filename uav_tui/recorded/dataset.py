"""Load a recorded run into pandas: ``uav_tui.recorded.dataset.load("runs/2026-05-01T10-00-00Z")``.

Example::

    from uav_tui.recorded import dataset

    run = dataset.load("runs/2026-05-01T10-00-00Z")
    run.frames[["frame_id", "north_m", "east_m", "roll_deg", "brightness"]]
    run.telemetry.plot(x="east_m", y="north_m")
    saved = run.frames[run.frames.saved]          # rows whose image is in run.path / saved.image
    people = run.detections[run.detections.label == "person"]          # one row per detection, by frame_id
    people.merge(run.frames[["frame_id", "rel_alt_m"]], on="frame_id")  # with the frame's telemetry

    both = dataset.compare("runs/<flight>", "runs/<its replay>")   # the same frames, side by side
    both[["t_s_a", "vx_a", "vx_b", "decision_a", "decision_b"]]

Every table is indexed by capture / receive time (a UTC ``DatetimeIndex`` named ``time``, from the
wall clock) and has ``t_s``, seconds since the run started on the monotonic clock (use it to compare
rows: the wall clock may be stepped by NTP). Frames carry the target's ground position (``target_lat_deg``,
``target_lon_deg``, ``target_alt_m``, ``target_uncertainty_m``, ``target_status``: see
:data:`uav_tui.recording.located.GEO_COLUMNS`; empty in runs recorded before). ``detections`` has a row per
detection the processor reported (``detections`` attribute), keyed by ``frame_id``, each geo-located the same way
(:data:`uav_tui.recording.located.DETECTION_COLUMNS`; no rows for a processor without detections). Nanosecond
columns are ``Int64``, flags ``boolean``, text ``string``; the ``tmMgr.save`` extras of ``frames.csv`` become one
column each. ``run.extrapolated`` lists the frames whose telemetry is not interpolated (held past the newest
sample or before the first) and by how much time.

A damaged run (power lost mid-write, a card copied half-way) loads with what can be read;
``run.problems`` says, one line each, which file, which line and what was wrong.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from uav_tui.errors import UavError
from uav_tui.recorded.run_files import Problem, read_json, read_table
from uav_tui.recording.located import DETECTION_COLUMNS
from uav_tui.recording.rows import EVENT_COLUMNS, FRAME_COLUMNS, SNAPSHOT_COLUMNS, TELEMETRY_COLUMNS

_TEXT = ("flight_mode", "gps_fix", "lock_state", "decision", "landing", "gimbal", "relayed", "error", "image", "extra",
         "telemetry", "level", "kind", "origin", "message", "command", "target_status", "target_height_from",
         "target_height_note", "label")
_FLAGS = ("armed", "in_air", "health_ok", "saved", "autonomy")
_INTEGERS = ("fc_boot_ms", "fc_clock_offset_ms", "satellites", "frame_id", "seq", "box_x", "box_y", "box_w", "box_h",
             "rangefinder_t_ns", "terrain_t_ns", "index", "track_id", "lock_track")


@dataclass(frozen=True)
class Dataset:
    """One recorded run."""

    path: Path
    info: dict[str, Any]
    """run.json: configuration, versions, source/processor/controller, start and end."""
    telemetry: pd.DataFrame
    """One row per telemetry update (columns: :data:`uav_tui.recording.TELEMETRY_COLUMNS`)."""
    frames: pd.DataFrame
    """One row per processed frame, with the telemetry interpolated to its capture time."""
    events: pd.DataFrame
    """Operator commands, autonomy decisions, warnings and errors."""
    problems: tuple[str, ...] = ()
    """What could not be read, one line each (file, line, what is wrong); empty for an intact run."""
    detections: pd.DataFrame = field(default_factory=lambda: pd.DataFrame(columns=list(DETECTION_COLUMNS)))
    """One row per detection the processor reported, keyed by ``frame_id`` (see the module's docstring)."""

    @property
    def extrapolated(self) -> pd.DataFrame:
        """The frames whose telemetry is not interpolated between samples around their capture: ``frame_id``,
        ``t_s``, ``telemetry`` (``held``: written without the sample after it, a link that stopped for longer
        than the recorder waits; ``before``: captured before the first sample) and ``extrapolated_ms``, how far
        the values reach past the telemetry (empty in runs recorded before it was written). Empty when every
        frame is bracketed, or the run had no vehicle."""
        frames = self.frames
        return frames.loc[frames["telemetry"].isin(["held", "before"]).fillna(False).to_numpy(dtype=bool),
                          ["frame_id", "t_s", "telemetry", "extrapolated_ms"]]

    @property
    def extra_columns(self) -> list[str]:
        """The frames columns that came from ``tmMgr.save(frame, **extra)``."""
        return list(self.info.get("extra_columns", []))


def load(run_dir: str | Path) -> Dataset:
    """Read a run folder (``runs/<UTC start>``) written by the recorder.

    Raises:
        UavError: ``run_dir`` is not a run folder.
    """
    path = Path(run_dir).expanduser()
    if not (path / "run.json").is_file():
        raise UavError(f"{path} is not a recorded run (no run.json); `uav-tui runs` lists the runs")
    info, problems = read_json(path / "run.json")
    info = _checked_info(info, path / "run.json", problems)
    tables = []
    for name, columns in (("telemetry", TELEMETRY_COLUMNS), ("frames", FRAME_COLUMNS),
                          ("events", EVENT_COLUMNS), ("detections", DETECTION_COLUMNS),
                          ("snapshots", SNAPSHOT_COLUMNS)):
        table, found = read_table(path / f"{name}.csv", columns, _dtype)
        tables.append(table)
        problems += found
    telemetry, frames, events, detections, snapshots = tables
    frames, extra_columns = _expand_extra(_with_snapshots(frames, snapshots), path / "frames.csv", problems)
    start = info.get("start_mono_ns")
    starts = [start] if isinstance(start, int) and start > 0 else [
        int(df["t_mono_ns"].min()) for df in (telemetry, frames, events) if df["t_mono_ns"].notna().any()]
    start_mono = min(starts) if starts else 0
    info = {**info, "extra_columns": extra_columns}
    return Dataset(path, info, _index(telemetry, start_mono), _index(frames, start_mono), _index(events, start_mono),
                   problems=tuple(str(problem) for problem in problems), detections=_index(detections, start_mono))


_SECTIONS = ("config", "source", "processor", "controller", "recording", "replay_of", "video", "versions")
"""The parts of run.json that are objects; anything else in their place is left out."""


def _with_snapshots(frames: pd.DataFrame, snapshots: pd.DataFrame) -> pd.DataFrame:
    """``frames`` with the ``snapshot`` commands' images marked (their rows may have been written before)."""
    taken = snapshots.dropna().drop_duplicates("frame_id", keep="last").set_index("frame_id")["image"]
    if taken.empty:
        return frames
    images = frames["frame_id"].map(taken)
    found = images.notna()
    frames.loc[found, "image"] = images[found]
    frames.loc[found, "saved"] = True
    return frames


def _checked_info(info: dict[str, Any], path: Path, problems: list[Problem]) -> dict[str, Any]:
    wrong = [key for key in _SECTIONS if key in info and not isinstance(info[key], dict)]
    wrong += [key for key in ("start_wall_ns", "end_wall_ns", "start_mono_ns")
              if key in info and (not isinstance(info[key], int) or isinstance(info[key], bool))]
    if wrong:
        problems.append(Problem(path, None, f"{', '.join(wrong)} {'is' if len(wrong) == 1 else 'are'} not what "
                                "uav-tui writes (left out)"))
    return {key: value for key, value in info.items() if key not in wrong}


def _dtype(name: str) -> str:
    if name.startswith("t_") and name.endswith("_ns"):
        return "Int64"
    if name in _INTEGERS:
        return "Int64"
    if name in _FLAGS:
        return "boolean"
    if name in _TEXT:
        return "string"
    return "float64"


def _expand_extra(frames: pd.DataFrame, path: Path, problems: list[Problem]) -> tuple[pd.DataFrame, list[str]]:
    """One column per ``tmMgr.save`` extra; names that clash with recorder columns get ``extra_``."""
    parsed, bad = [], []
    for frame_id, text in zip(frames["frame_id"], frames["extra"], strict=True):
        try:
            fields = json.loads(text) if isinstance(text, str) and text else {}
        except ValueError:
            fields = None
        if not isinstance(fields, dict):
            bad.append(frame_id)
            fields = {}
        parsed.append(fields)
    if bad:
        problems.append(Problem(path, None, f"the extra of frame_id {bad[0]} is not a JSON object (left empty)"
                                + (f" (and {len(bad) - 1} more such)" if len(bad) > 1 else "")))
    keys = list(dict.fromkeys(key for fields in parsed for key in fields))
    if not keys:
        return frames, []
    names = {key: f"extra_{key}" if key in frames.columns else key for key in keys}
    table = pd.DataFrame([{names[k]: v for k, v in fields.items()} for fields in parsed], index=frames.index,
                         columns=list(names.values()), dtype=object)
    table = table.apply(_best_dtype)
    return pd.concat([frames, table], axis=1), list(names.values())


def _best_dtype(column: pd.Series) -> pd.Series:
    values = column.dropna()
    if values.map(lambda v: isinstance(v, bool)).all() and len(values):
        return column.astype("boolean")
    if values.map(lambda v: isinstance(v, int) and not isinstance(v, bool)).all():
        return column.astype("Int64")
    if values.map(lambda v: isinstance(v, int | float) and not isinstance(v, bool)).all():
        return pd.to_numeric(column).astype("float64")
    if values.map(lambda v: isinstance(v, str)).all():
        return column.astype("string")
    return column  # lists and mixed values stay Python objects


def _index(table: pd.DataFrame, start_mono_ns: int) -> pd.DataFrame:
    table = table.copy()
    table.insert(0, "t_s", (table["t_mono_ns"].astype("float64") - start_mono_ns) / 1e9)
    wall = table["t_wall_ns"].fillna(0).to_numpy(dtype="int64")
    table.index = pd.DatetimeIndex(pd.to_datetime(wall, unit="ns", utc=True), name="time")
    return table


def compare(run_a: str | Path | Dataset, run_b: str | Path | Dataset, *, how: str = "inner") -> pd.DataFrame:
    """The frames two runs of the same flight share (a flight and its replays), joined on capture time.

    Every frames column appears twice, with the suffix ``_a`` (from ``run_a``) and ``_b``, except
    ``t_mono_ns``, the capture time both rows carry; the index is ``run_a``'s time. ``how="outer"``
    keeps frames only one run processed (a paced replay skips frames a slow processor could not take).
    """
    frames_a, frames_b = (_as_dataset(run).frames for run in (run_a, run_b))
    left = frames_a.add_suffix("_a").rename(columns={"t_mono_ns_a": "t_mono_ns"})
    right = frames_b.add_suffix("_b").rename(columns={"t_mono_ns_b": "t_mono_ns"}).reset_index(drop=True)
    joined = left.reset_index().merge(right, on="t_mono_ns", how=how, validate="one_to_one")
    return joined.set_index("time").sort_values("t_mono_ns")


def _as_dataset(run: str | Path | Dataset) -> Dataset:
    return run if isinstance(run, Dataset) else load(run)
