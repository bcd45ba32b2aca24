"""The three CSV tables: their columns, their rows, and frames held back until telemetry brackets them."""

from __future__ import annotations

import json
import math
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from controllers.base import TELEMETRY_FIELDS, Telemetry
from uav_tui.events import Event
from uav_tui.flight.geolocate import locate_row
from uav_tui.output.text import last_line, shorten
from uav_tui.recording.interpolate import FIELDS, KEEP_NS, TelemetryHistory
from uav_tui.recording.located import DETECTION_COLUMNS, GEO_COLUMNS, detection_rows, geo_cells
from uav_tui.recording.writer import Row

if TYPE_CHECKING:
    from uav_tui.relays.contract import HandledFrame
    from uav_values.camera import CameraModel
    from uav_values.detections import Detected

TELEMETRY_COLUMNS: tuple[str, ...] = TELEMETRY_FIELDS
"""telemetry.csv: one row per telemetry update; ``t_mono_ns``/``t_wall_ns`` are when it was received."""

EVENT_COLUMNS: tuple[str, ...] = ("t_wall_ns", "t_mono_ns", "level", "kind", "origin", "message", "command",
                                  "autonomy")
"""events.csv: one row per :class:`uav_tui.events.Event`; ``command`` names the operator command an outcome
or error row reports on; ``autonomy`` is True or False where autonomy was switched on or off, else empty."""

FRAME_OWN_COLUMNS: tuple[str, ...] = (
    "frame_id", "seq", "t_wall_ns", "t_mono_ns", "t_start_ns", "t_end_ns", "t_vector_ns", "vx", "vy", "vt",
    "box_x", "box_y", "box_w", "box_h", "lock_track", "lock_state", "decision", "landing", "gimbal", "relayed", "error",
    "saved", "image", "extra", "telemetry", "extrapolated_ms",
)
"""frames.csv, the frame's own part: ids, capture times (wall + monotonic ns), processing stage times
(monotonic ns), the vector, the processor's ``box`` (frame pixels, empty when None; the locked track's while the
operator's lock is on), the track the lock was on and its state (``locked`` or ``lost``; both empty without one),
the autonomy decision, what was done with the processor's landing target and with its gimbal pointing (each ``sent`` or
``not sent: why``; empty without one) and with any further output (``relayed``: JSON, its field -> what was done;
empty without), the last line of an exception, whether and where the image was saved, the ``tmMgr.save`` extras
as JSON, how the telemetry columns were obtained (``interpolated``, ``held``, ``before``, ``none``; see
:meth:`TelemetryHistory.at`) and, when ``held`` or ``before``, how far past the telemetry the row reaches
(:meth:`TelemetryHistory.extrapolated_ns`, in ms: the row was written without the sample after it)."""

FRAME_COLUMNS: tuple[str, ...] = FRAME_OWN_COLUMNS + FIELDS + GEO_COLUMNS
"""frames.csv: the frame's own columns, the telemetry interpolated to the capture time, where the centre of ``box``
is on the ground (:data:`~uav_tui.recording.located.GEO_COLUMNS`)."""

MAX_ERROR_CHARS = 500
"""The ``error`` column keeps this much of an exception's last line."""

_SAVED = FRAME_OWN_COLUMNS.index("saved")  # followed by "image"
_BOX = FRAME_OWN_COLUMNS.index("box_x")  # then box_y, box_w, box_h
_T_WALL = FRAME_OWN_COLUMNS.index("t_wall_ns")

SNAPSHOT_COLUMNS = ("frame_id", "image")
"""snapshots.csv: a row per ``snapshot`` command's image, whether or not its frame's row still showed it."""

TABLES: dict[str, tuple[str, ...]] = {"telemetry": TELEMETRY_COLUMNS, "frames": FRAME_COLUMNS, "events": EVENT_COLUMNS,
                                      "detections": DETECTION_COLUMNS, "snapshots": SNAPSHOT_COLUMNS}


def image_name(frame_id: int) -> str:
    """Where frame ``frame_id``'s image goes, relative to the run folder."""
    return f"frames/{frame_id:06d}.jpg"


@dataclass(slots=True)
class FrameRecord:
    """A frame's own columns, waiting on the writer thread for the telemetry around its capture."""

    values: list[Any]
    t_mono_ns: int
    camera: CameraModel | None = None
    """The frame's camera model (geo-locates ``box`` once the telemetry is known)."""
    detections: tuple[Detected, ...] = ()
    """The processor's ``detections`` on this frame (detections.csv rows once the telemetry is known)."""

    @property
    def frame_id(self) -> int:
        return self.values[0]


@dataclass(slots=True)
class TelemetrySample:
    """One telemetry snapshot and the monotonic time it was received."""

    telemetry: Telemetry
    t_mono_ns: int


@dataclass(slots=True)
class MarkSaved:
    """Frame ``frame_id``'s image was saved after its row was built (the ``snapshot`` command)."""

    frame_id: int
    image: str


OWN_COLUMN_OUTPUTS = ("landing_target", "gimbal")
"""The outputs whose relay's verdict has its own column (``landing``, ``gimbal``); the others' go in ``relayed``."""


def frame_record(result: HandledFrame, frame_id: int, image: str, extra_json: str,
                 camera: CameraModel | None = None) -> FrameRecord:
    """The own columns of a processed frame (:data:`FRAME_OWN_COLUMNS` up to ``extra``) and its camera model."""
    frame = result.frame
    vx, vy, vt = _vector(result.outcome.vector)
    error = shorten(last_line(result.outcome.error), MAX_ERROR_CHARS) if result.outcome.error else ""
    box = result.outcome.box or (None, None, None, None)
    lock = (None, "") if result.lock is None else (result.lock.track_id, result.lock.state.value)
    further = {name: verdict for name, verdict in result.relayed.items() if name not in OWN_COLUMN_OUTPUTS}
    values = [frame_id, frame.seq, frame.t_wall_ns, frame.t_mono_ns, result.outcome.t_start_ns, result.outcome.t_end_ns,
              result.outcome.t_vector_ns or None, vx, vy, vt, *box, *lock, result.decision, result.landing,
              result.gimbal, json.dumps(further) if further else "", error, bool(image), image,
              extra_json]
    return FrameRecord(values, frame.t_mono_ns, camera, result.outcome.detections or ())


def event_row(event: Event) -> Row:
    return Row("events", [event.t_wall_ns, event.t_mono_ns, event.level, event.kind, event.origin, event.message,
                          event.command, event.autonomy])


def telemetry_row(sample: TelemetrySample) -> Row:
    return Row("telemetry", [getattr(sample.telemetry, name) for name in TELEMETRY_FIELDS])


def extra_json(extra: dict[str, Any]) -> str:
    """``tmMgr.save`` extras as one JSON object (NumPy scalars and small arrays become numbers and lists)."""
    return json.dumps(extra, default=_plain, allow_nan=True) if extra else ""


def _plain(value: Any) -> Any:
    if isinstance(value, np.generic | np.ndarray):
        return value.tolist()
    if isinstance(value, set | frozenset | tuple):
        return list(value)
    return str(value)


def _vector(vector: Any) -> tuple[float | None, float | None, float | None]:
    """The three numbers of a vector if it is one (the gate judges it; the row just records it)."""
    try:
        vx, vy, vt = (float(v) for v in vector)
    except (TypeError, ValueError, OverflowError):
        return None, None, None
    return vx, vy, vt


HOLD_NS = KEEP_NS
"""Longest a frame row waits for the telemetry after its capture (5 s: as long as the writer keeps the history
the row is interpolated from): telemetry held up this long by a busy computer (a starved
``mavsdk_server``, a loop running late) still brackets the frames captured meanwhile; only a link that stops
for longer leaves rows ``held``."""


class FrameAligner:
    """Writer-thread stage: telemetry rows go out at once, frame rows once telemetry brackets them.

    A frame waits until every continuous telemetry field has a sample after its capture time (or has
    been constant a while: :meth:`TelemetryHistory.covers`), so it is interpolated, not extrapolated,
    however late the telemetry reaches the writer. Only when ``hold_ns`` passed since capture without
    it is the row written with the newest values held, marked ``held`` with how far it reaches
    (``extrapolated_ms``). Every frame waits at least ``min_hold_ns``, so a ``snapshot`` of the newest
    frame usually still finds its row and marks it saved; every snapshot is also a snapshots.csv row, which
    :func:`uav_tui.recorded.dataset.load` merges into ``saved`` and ``image`` (a row already written: a processor
    slower than ``min_hold_ns`` a frame, or a snapshot taken later).

    A row written once the telemetry brackets it holds the same values whenever that was (later samples
    do not change an interpolation between earlier ones), so it equals the interpolation from the whole
    ``telemetry.csv``, and a replay computes the same row.

    A row's ``saved`` says whether its image file is on disk when the row is written (images are
    queued before their rows, so a frame dropped by a full disk or the size cap is not claimed).

    Args:
        hold_ns: longest wait for telemetry after a capture (:data:`HOLD_NS`).
        min_hold_ns: shortest wait.
        telemetry_expected: False with ``--fc none``: frames wait only ``min_hold_ns``.
        run_dir: where image names point (None: do not check the files).
        recorded_clock: a replay: ticks read the newest capture or receive time handled, not this
            computer's clock, so rows are released as they were in the recorded run, at any speed.
    """

    accepts: tuple[type, ...] = (TelemetrySample, FrameRecord, MarkSaved)

    def __init__(self, hold_ns: int = HOLD_NS, min_hold_ns: int = 200_000_000,
                 telemetry_expected: bool = True, run_dir: Path | None = None, recorded_clock: bool = False) -> None:
        self.hold_ns = hold_ns
        self.min_hold_ns = min_hold_ns
        self.run_dir = run_dir
        self.telemetry_expected = telemetry_expected
        self.recorded_clock = recorded_clock
        self.history = TelemetryHistory()
        self._waiting: deque[FrameRecord] = deque()
        self._newest_ns = 0

    def handle(self, item: Any) -> Iterable[Row]:
        if isinstance(item, TelemetrySample):
            self.history.add(item.telemetry, item.t_mono_ns)
            self._newest_ns = max(self._newest_ns, item.t_mono_ns)
            return [*self._release(item.t_mono_ns), telemetry_row(item)]
        if isinstance(item, FrameRecord):
            self._waiting.append(item)
            self._newest_ns = max(self._newest_ns, item.t_mono_ns)
        elif isinstance(item, MarkSaved):  # the frame's row may be written already (a slow processor): snapshots.csv
            if self.run_dir is not None and not (self.run_dir / item.image).is_file():
                return []  # not on disk (a full disk, the size cap): not claimed
            for record in self._waiting:
                if record.frame_id == item.frame_id:
                    record.values[_SAVED:_SAVED + 2] = [True, item.image]
            return [Row("snapshots", [item.frame_id, item.image])]
        else:
            raise TypeError(f"FrameAligner cannot handle {type(item).__name__}")
        return []

    def due(self, now_ns: int) -> Iterable[Row]:
        return self._release(self._newest_ns if self.recorded_clock else now_ns, timed_out=self.telemetry_expected)

    def _release(self, now_ns: int, *, timed_out: bool = False) -> list[Row]:
        """Rows ready at ``now_ns``: covered ones that waited ``min_hold_ns``; if ``timed_out``, also those that
        waited ``hold_ns``."""
        rows = []
        while self._waiting:
            record = self._waiting[0]
            age = now_ns - record.t_mono_ns
            if age < self.min_hold_ns or self.telemetry_expected and not self.history.covers(record.t_mono_ns) and (
                    not timed_out or age < self.hold_ns):
                break
            rows += self._rows(self._waiting.popleft())
        return rows

    def drain(self) -> Iterable[Row]:
        rows = [row for record in self._waiting for row in self._rows(record)]
        self._waiting.clear()
        return rows

    def _rows(self, record: FrameRecord) -> list[Row]:
        """The frames.csv row of ``record``, then a detections.csv row per detection."""
        image = record.values[_SAVED + 1]
        if image and self.run_dir is not None and not (self.run_dir / image).is_file():
            record.values[_SAVED:_SAVED + 2] = [False, ""]
        values, how = self.history.at(record.t_mono_ns)
        reach = self.history.extrapolated_ns(record.t_mono_ns) if how in ("held", "before") else None
        x, y, w, h = record.values[_BOX:_BOX + 4]
        fix = locate_row(record.camera, None if x is None else (x, y, w, h), values, at_ns=record.t_mono_ns)
        frame = Row("frames", [*record.values, how, None if reach is None else round(reach / 1e6, 1),
                               *(_finite(values[name]) for name in FIELDS), *geo_cells(fix)])
        t_wall_ns = record.values[_T_WALL]
        return [frame, *(Row("detections", cells) for cells in detection_rows(
            record.frame_id, t_wall_ns, record.t_mono_ns, record.detections, record.camera, values))]


def _finite(value: Any) -> Any:
    return None if isinstance(value, float) and not math.isfinite(value) else value
