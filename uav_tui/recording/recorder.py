"""The Recorder: joins a running core to the disk writer, one folder per run.

Threads: ``save`` runs on the processor thread (it is ``tmMgr.saver``; with process isolation the
child's saves are replayed on the event loop, just before their frame's result); ``on_frame``,
``on_telemetry``, ``on_event`` and ``snapshot`` on the event loop; all of them only queue work. The
writer thread encodes, interpolates, geo-locates the box and writes. ``open`` and ``close`` block: run
them in an executor.

Frame ids count processed frames from 1 for the whole run, in processing order, so they stay unique
when the camera is switched (a new source's ``seq`` starts at 1 again). An id is given on the loop
when the frame's result arrives; ``tmMgr.save`` runs earlier, on the processor thread, so its image is
written under a provisional name in ``.pending/`` and renamed to ``frames/<id>.jpg`` by the writer
thread once the id is known (the writer handles items in order: image, rename, row).
"""

from __future__ import annotations

import itertools
import logging
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from controllers.base import Telemetry
from sources.buffer import Frame
from uav_tui.config import RecordingConfig
from uav_tui.errors import UavError
from uav_tui.events import Event, EventLog, Level
from uav_tui.hosting.host import ProcessorHost
from uav_tui.recording.crash import CrashRecord
from uav_tui.recording.reserve import DiskReserve, free_stale_reserves
from uav_tui.recording.rows import (
    TABLES,
    FrameAligner,
    MarkSaved,
    TelemetrySample,
    event_row,
    extra_json,
    frame_record,
    image_name,
)
from uav_tui.recording.run_info import new_run_dir, write_json
from uav_tui.recording.video import (
    INDEX_COLUMNS,
    INDEX_TABLE,
    FrameLink,
    VideoDrop,
    VideoFrame,
    VideoStage,
    describe_video,
)
from uav_tui.recording.writer import MB, DiskWriter, Rename

if TYPE_CHECKING:
    from sources import CameraSource
    from uav_tui.camera.active import ActiveCamera
    from uav_tui.flight.telemetry import TelemetryManager
    from uav_tui.relays.contract import HandledFrame
    from uav_values.camera import CameraModel

logger = logging.getLogger(__name__)

PENDING = ".pending"
"""Run sub-folder for images saved before their frame id was known."""


class NotRecording:
    """``tmMgr.save`` with ``--no-record``: says once in the event log (not on the terminal) that it stores nothing."""

    def __init__(self, events: EventLog) -> None:
        self.events = events
        self.told = False

    def __call__(self, frame: Any, extra: dict[str, Any]) -> None:
        if not self.told:
            self.told = True
            self.events.emit("info", "recorder", "recording is off (--no-record): tmMgr.save() stores nothing")


@dataclass(slots=True)
class _Save:
    frame: Frame
    pending: str = ""
    """Provisional image name (``.pending/<n>.jpg``), empty when the image was dropped."""
    extra: dict[str, Any] = field(default_factory=dict)


class Recorder:
    """Writes one run: ``telemetry.csv``, ``frames.csv``, ``frames/<id>.jpg``, ``events.csv``, ``run.json``.

    Args:
        run_dir: the run folder (created by :meth:`open`).
        config: the recording section of the configuration.
        info: what ``run.json`` says about the run (config, versions, source, processor, controller).
        telemetry_expected: False without a flight controller: frame rows need not wait for telemetry.
        writer_factory: builds the writer (default :class:`DiskWriter`; tests pass a throttled one).
        replayed: the run replays a recorded one: rows follow the recorded clock (see :class:`FrameAligner`).
    """

    def __init__(self, run_dir: Path, config: RecordingConfig, info: dict[str, Any], *,
                 telemetry_expected: bool, writer_factory: Callable[..., DiskWriter] | None = None,
                 replayed: bool = False) -> None:
        self.run_dir = run_dir
        self.config = config
        self.info = info
        self.frames = 0
        """Processed frames seen (rows queued)."""
        self.misplaced_saves = 0
        """``tmMgr.save`` calls made outside ``photo_processing`` (ignored)."""
        self.crash: CrashRecord | None = None
        self.reserve: DiskReserve | None = None
        """Disk space held for the final ``run.json`` while the run is open (set by :meth:`open`)."""
        """Where a crash of this process writes its stacks while the run is open (set by :meth:`open`)."""
        self._emit: Callable[[Level, str], object] = lambda level, message: None
        self._current: Callable[[], Frame | None] = lambda: None
        self._camera: Callable[[], CameraModel | None] = lambda: None
        self._ids = itertools.count(1)
        self._provisional = itertools.count(1)
        self._saves: dict[int, _Save] = {}
        self._last: tuple[HandledFrame, int] | None = None
        self._watched: CameraSource | None = None
        aligner = FrameAligner(telemetry_expected=telemetry_expected, run_dir=run_dir, recorded_clock=replayed)
        tables = {**TABLES, INDEX_TABLE: INDEX_COLUMNS} if config.record_video else TABLES
        self.writer = (writer_factory or DiskWriter)(
            run_dir, tables, stages=[aligner], jpeg_quality=config.jpeg_quality,
            max_disk_bytes=int(config.max_disk_mb * MB), min_free_bytes=int(config.min_free_mb * MB),
            on_problem=self._problem)
        self.video = VideoStage(self.writer) if config.record_video else None
        """Encodes the camera stream into ``video.ts`` (None when ``record_video`` is off)."""
        if self.video is not None:
            self.writer.stages.append(self.video)

    @classmethod
    def open(cls, config: RecordingConfig, info: dict[str, Any], *, telemetry_expected: bool,
             started_wall_ns: int | None = None, **kwargs: Any) -> Recorder:
        """Create ``runs_dir/<UTC start>/`` with its ``run.json`` and start the writer thread. Blocks.

        Raises:
            UavError: the folder cannot be created (says which and what to do).
        """
        started = started_wall_ns or time.time_ns()
        try:
            runs_dir = Path(config.runs_dir).expanduser().resolve()
            if runs_dir.is_dir():
                free_stale_reserves(runs_dir)
            run_dir = new_run_dir(runs_dir, started)
            (run_dir / "frames").mkdir()
            (run_dir / PENDING).mkdir()
            info = {**info, "start_wall_ns": started, "start_mono_ns": time.monotonic_ns()}
            if config.record_video:
                info["video"] = describe_video()
            recorder = cls(run_dir, config, info, telemetry_expected=telemetry_expected, **kwargs)
            write_json(run_dir / "run.json", recorder.info)
            recorder.reserve = DiskReserve(run_dir)
        except OSError as exc:
            raise UavError(f"cannot create the run folder under {config.runs_dir}: {exc.strerror or exc}; "
                           "choose another with --runs-dir, or run with --no-record") from exc
        recorder.writer.start()
        recorder.crash = CrashRecord(run_dir)
        logger.info("Recorder(%s): recording", run_dir)
        return recorder

    def attach(self, events: EventLog, telemetry: TelemetryManager, worker: ProcessorHost,
               camera: ActiveCamera) -> None:
        """Record every event and ``telemetry``'s samples, become its ``tmMgr`` saver (a save is of ``worker``'s
        current frame) and record the video of ``camera``'s source; each processed frame comes to :meth:`on_frame`
        (a frame listener the core adds)."""
        self._emit = lambda level, message: events.emit(level, "recorder", message)
        self._current = lambda: worker.current  # the frame whose saves are being made, None between frames
        self._camera = lambda: camera.model  # the model of the source the frames come from (it follows a switch)
        telemetry.saver = self.save
        telemetry.add_listener(self.on_telemetry)
        for event in events.recent:  # what happened before the recorder existed (e.g. a source warning)
            self.on_event(event)
        events.add_listener(self.on_event)
        if camera.source is not None:
            self.watch(camera.source)

    def watch(self, source: CameraSource) -> None:
        """Record ``source``'s frames into the video from now on (the camera was switched). Call it before
        the processor worker attaches to the source, so each frame is copied before it may be drawn on."""
        if self.video is None:
            return
        if self._watched is not None:
            self._watched.buffer.remove_listener(self._on_capture)
        self._watched = source
        source.buffer.add_listener(self._on_capture)

    # -- capture thread --------------------------------------------------------------------------

    def _on_capture(self, frame: Frame) -> None:
        """Queue a copy of the frame as captured, before the processor can draw on it (~0.1 ms at 640x480)."""
        reason = self.writer.put_pixels(VideoFrame(frame.image, frame.seq, frame.t_mono_ns, frame.t_wall_ns),
                                        copy=True)
        if reason is not None and reason != "closed":
            self.writer.put(VideoDrop(frame.seq, frame.t_mono_ns, frame.t_wall_ns, reason))

    # -- processor thread ------------------------------------------------------------------------

    def save(self, image: Any, extra: dict[str, Any]) -> None:
        """``tmMgr.save(frame, **extra)``: queue the image and put ``extra`` in its frame's row.

        The pixels are copied here: the processor may go on drawing on its array (or reuse it for
        the next frame) while the writer thread encodes, and a copy (~0.3 ms for 640x480) costs far
        less than encoding on this thread would.
        """
        frame = self._current()
        if frame is None:
            self.misplaced_saves += 1
            if self.misplaced_saves == 1:
                self._emit("warning", "tmMgr.save() called outside photo_processing(): ignored (it stores "
                                      "the frame being processed)")
            return
        image = image.image if isinstance(image, Frame) else image  # a sources Frame is fine too
        if not isinstance(image, np.ndarray) or image.ndim not in (2, 3):
            raise TypeError(f"tmMgr.save(frame, **extra): frame must be an image array, got {type(image).__name__}")
        entry = self._saves.get(id(frame))
        if entry is None or entry.frame is not frame:
            entry = self._saves[id(frame)] = _Save(frame)
        entry.extra.update(extra)
        name = entry.pending or f"{PENDING}/{next(self._provisional)}.jpg"
        if self.writer.put_image(name, image, copy=True):
            entry.pending = name

    # -- event loop ------------------------------------------------------------------------------

    def on_frame(self, result: HandledFrame) -> None:
        """Queue the frame's row (and every Nth frame's image when ``record_every`` is set)."""
        frame_id = next(self._ids)
        name = image_name(frame_id)
        entry = self._saves.pop(id(result.frame), None)
        if entry is not None and entry.frame is result.frame:
            extra = extra_json(entry.extra)
            image = name if entry.pending and self.writer.put(Rename(entry.pending, name)) else ""
        else:
            extra, image = "", ""
            every = self.config.record_every
            # The processor is done with this array and sources hand out a new one per capture: no copy.
            if every and frame_id % every == 0 and self.writer.put_image(name, result.frame.image):
                image = name
        self.frames += 1
        self._last = (result, frame_id)
        self.writer.put(frame_record(result, frame_id, image, extra, self._camera()))
        if self.video is not None:
            self.writer.put(FrameLink(result.frame.t_mono_ns, frame_id))

    def on_telemetry(self, telemetry: Telemetry) -> None:
        t_mono = telemetry.t_mono_ns or time.monotonic_ns()
        self.writer.put(TelemetrySample(telemetry, t_mono))

    def on_event(self, event: Event) -> None:
        self.writer.put(event_row(event))

    def snapshot(self) -> str:
        """Save the newest processed frame's image into the run; returns what was saved.

        Raises:
            UavError: no frame was processed yet, or the frame was dropped (says why).
        """
        if self._last is None:
            raise UavError("snapshot: no frame has been processed yet")
        result, frame_id = self._last
        name = image_name(frame_id)
        if not self.writer.put_image(name, result.frame.image, copy=True):
            reason = self.writer.image_refused() or "the recorder queue is full"
            raise UavError(f"snapshot of frame {frame_id} not saved: {reason}")
        self.writer.put(MarkSaved(frame_id, name))
        return f"frame {frame_id} saved as {self.run_dir / name}"

    def status(self) -> dict[str, Any]:
        """For ``CoreStatus.recording``: run folder, frames, images saved, rows written, drops."""
        writer = self.writer
        return {"run_dir": str(self.run_dir), "frames": self.frames, "frames_saved": writer.images_written,
                "rows_written": dict(writer.rows_written), "bytes": writer.bytes_written,
                "video_frames": self.video.frames_encoded if self.video is not None else None,
                "dropped": writer.dropped_total, "drops": dict(writer.dropped), "lost": dict(writer.lost)}

    def close(self, end: dict[str, Any] | None = None) -> None:
        """Write everything queued, then finish ``run.json`` with the end time and counts. Blocks."""
        if self._watched is not None:
            self._watched.buffer.remove_listener(self._on_capture)
        self.writer.close()
        # Images of frames whose results never arrived (in flight at the stop) have no row: drop them.
        shutil.rmtree(self.run_dir / PENDING, ignore_errors=True)
        if self.reserve is not None:
            self.reserve.release()
        self.info.update(end or {}, end_wall_ns=time.time_ns(), recording=self.status())
        try:
            write_json(self.run_dir / "run.json", self.info)
        except OSError as exc:
            logger.error("Recorder(%s): cannot finish run.json: %s", self.run_dir, exc)
        if self.incomplete:
            self._emit("error", f"the run is incomplete: {describe_lost(self.writer.lost)} could not be written (the "
                       f"disk was full or failing); what was written is intact, run.json counts the losses")
        if self.crash is not None:
            self.crash.close()

    @property
    def incomplete(self) -> bool:
        """True when a disk error (full, failing) kept something from the run (not the limits set)."""
        return bool(self.writer.lost)

    def _problem(self, reason: str, message: str) -> None:
        logger.warning("Recorder(%s): %s", self.run_dir, message)
        self._emit("error" if reason in ("disk_full", "write_error") else "warning", message)


def describe_lost(lost: dict[str, int]) -> str:
    """``120 frame images, 340 frames.csv rows and 5.2 MB of video``."""
    parts = [f"{amount / 1e6:.1f} MB of video" if what == "video bytes" else f"{amount} {what}"
             for what, amount in lost.items()]
    return ", ".join(parts[:-1]) + (" and " if len(parts) > 1 else "") + parts[-1]
