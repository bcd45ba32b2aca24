"""The disk writer: one thread behind a bounded queue; nothing that feeds it ever waits for the disk.

Items are CSV rows (:class:`Row`), JPEG frames (queued with :meth:`DiskWriter.put_image`), renames
of written files (:class:`Rename`) or anything one of its :class:`Stage` objects accepts (stages run
on the writer thread and turn items into rows; images for a stage go through :meth:`DiskWriter.put_pixels`).
Items are handled in the order they were queued. When
the queue is full, the disk is full, the run folder reached its size cap or the disk its free-space
floor, the item is dropped and counted, and the first drop of each kind is reported once through
``on_problem``.

CSV files only ever receive whole lines (:class:`~uav_tui.recording.csv_files.CsvFiles`): rows are
appended every ``flush_s``, so a process killed with SIGKILL leaves valid CSV up to its last flush.
JPEGs are written to a temporary name and renamed, so a frame file is either complete or absent.
"""

from __future__ import annotations

import errno
import logging
import os
import queue
import shutil
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import cv2
import numpy as np

from uav_tui.recording.csv_files import CsvFiles

logger = logging.getLogger(__name__)

MB = 1024 * 1024

_IDLE = object()


@dataclass(slots=True)
class Row:
    """One CSV row for ``table`` (a file ``<table>.csv``), values in the table's column order."""

    table: str
    values: list[Any]


@dataclass(slots=True)
class Rename:
    """Move ``source`` to ``target`` (paths relative to the run folder) if ``source`` was written."""

    source: str
    target: str


@dataclass(slots=True)
class Pixels:
    """A queued item holding an image: counted against ``max_image_bytes`` until the writer handled it."""

    image: np.ndarray


@dataclass(slots=True)
class _Image(Pixels):
    name: str = ""


class Stage(Protocol):
    """Turns queued items into rows on the writer thread (e.g. frames waiting for telemetry)."""

    accepts: tuple[type, ...]
    """The item types this stage handles."""

    def handle(self, item: Any) -> Iterable[Row]:
        """Rows that ``item`` produces at once."""
        ...

    def due(self, now_ns: int) -> Iterable[Row]:
        """Rows that became ready by ``now_ns`` (monotonic)."""
        ...

    def drain(self) -> Iterable[Row]:
        """Everything still held back (the run ends)."""
        ...


PROBLEMS = {
    "queue_full": "the recorder cannot keep up with the disk: items are being dropped",
    "disk_full": "the disk is full: items are being dropped (rows already written are intact)",
    "disk_cap": "the run folder reached max_disk_mb: nothing more is recorded (frames, rows)",
    "min_free": "free disk space is below min_free_mb: nothing more is recorded (frames, rows)",
    "write_error": "a write failed",
}
"""Drop reason -> what the operator is told the first time it happens."""
DISK_ERRORS = frozenset({"disk_full", "write_error"})
"""Drop reasons that leave the run incomplete against the operator's settings (the disk failed it)."""


class DiskWriter:
    """Writes CSV tables and JPEG frames into ``run_dir`` from one named daemon thread.

    Args:
        run_dir: the run folder (exists).
        tables: table name -> column names (the header written when the file is created).
        stages: item -> rows converters run on the writer thread (more can be appended before ``start``).
        jpeg_quality: 10..100.
        max_disk_bytes: stop writing (frames and rows) once this much was written (0: no cap).
        min_free_bytes: stop writing (frames and rows) when the disk has less free space.
        on_problem: ``on_problem(reason, message)``, called once per drop reason, from any thread.
        max_items: queue length.
        max_image_bytes: image bytes allowed to wait in the queue at once.
        flush_s: how often collected rows are appended to the files.
    """

    def __init__(self, run_dir: Path, tables: Mapping[str, Sequence[str]], *, stages: Sequence[Stage] = (),
                 jpeg_quality: int = 90, max_disk_bytes: int = 0, min_free_bytes: int = 0,
                 on_problem: Callable[[str, str], None] | None = None, max_items: int = 4096,
                 max_image_bytes: int = 48 * MB, flush_s: float = 0.5) -> None:
        self.run_dir = Path(run_dir)
        self.stages = list(stages)
        self.jpeg_quality = jpeg_quality
        self.max_disk_bytes = max_disk_bytes
        self.min_free_bytes = min_free_bytes
        self.flush_s = flush_s
        self.max_image_bytes = max_image_bytes
        self.images_written = 0
        self.bytes_written = 0
        """Everything this writer put on disk (run folder size, apart from run.json)."""
        self.dropped: dict[str, int] = {}
        """Drop reason -> items dropped."""
        self.lost: dict[str, int] = {}
        """What a disk error (full, failing) kept from the disk: ``frame images``, ``<table>.csv rows``, ``video bytes``
        ... -> how many. Empty when the run is complete (drops at the limits set, ``max_disk_mb`` or ``min_free_mb``,
        and drops of a queue that could not keep up are not errors of the disk)."""
        self._on_problem = on_problem
        self._queue: queue.Queue[Any] = queue.Queue(max_items)
        self._lock = threading.Lock()
        self._image_bytes_queued = 0
        self._free_bytes = self._disk_free()
        self._csv = CsvFiles(self.run_dir, tables, self._write)
        self._thread = threading.Thread(target=self._run, name=f"recorder-writer:{self.run_dir.name}", daemon=True)
        self._closed = False

    # -- any thread ------------------------------------------------------------------------------

    def start(self) -> None:
        self._thread.start()

    def put(self, item: Any) -> bool:
        """Queue a :class:`Row` or a stage item; False when it was dropped."""
        if self._closed:
            return False
        try:
            self._queue.put_nowait(item)
        except queue.Full:
            self._drop("queue_full")
            return False
        return True

    def put_image(self, name: str, image: np.ndarray, *, copy: bool = False) -> bool:
        """Queue ``image`` to be JPEG-encoded into ``run_dir/name``; False when it was dropped.

        The guards (size cap, free space, queued image bytes) are checked before anything is copied.
        With ``copy=True`` the pixels are copied first, so the caller may go on changing its array.
        """
        if self._reserve(image.nbytes) is not None:
            return False
        return self._put_reserved(_Image(image.copy() if copy else image, name))

    def put_pixels(self, item: Pixels, *, copy: bool = False) -> str | None:
        """Queue a stage's item that holds an image, under the guards of :meth:`put_image`.

        Returns None when it was queued, else why it was dropped (counted like a dropped image).
        With ``copy=True`` the pixels are copied once the guards let them in.
        """
        reason = self._reserve(item.image.nbytes)
        if reason is None and copy:
            item.image = item.image.copy()
        if reason is None and not self._put_reserved(item):
            reason = "queue_full"
        return reason

    def _reserve(self, nbytes: int) -> str | None:
        reason = self.image_refused()
        if reason is None:
            with self._lock:
                if self._image_bytes_queued + nbytes > self.max_image_bytes:
                    reason = "queue_full"
                else:
                    self._image_bytes_queued += nbytes
        if reason is not None:
            self._drop(reason)
        return reason

    def _put_reserved(self, item: Pixels) -> bool:
        if self.put(item):
            return True
        self._image_done(item.image.nbytes)
        return False

    def image_refused(self) -> str | None:
        """Why a frame would be dropped now (``closed``, ``disk_cap``, ``min_free``), None if it would be taken."""
        return "closed" if self._closed else self._space_refused()

    def _space_refused(self) -> str | None:
        """``disk_cap`` or ``min_free`` when the disk guards refuse any more writing, else None."""
        if self.max_disk_bytes and self.bytes_written >= self.max_disk_bytes:
            return "disk_cap"
        if self.min_free_bytes and self._free_bytes < self.min_free_bytes:
            return "min_free"
        return None

    @property
    def rows_written(self) -> dict[str, int]:
        """Rows on disk per table."""
        return self._csv.rows_written

    @property
    def dropped_total(self) -> int:
        return sum(self.dropped.values())

    def close(self, timeout: float = 10.0) -> None:
        """Write what is queued, flush, close the files. Blocks (call it off the event loop); idempotent."""
        if self._closed:
            return
        self._closed = True
        if self._thread.is_alive():
            try:
                self._queue.put(None, timeout=timeout)
            except queue.Full:
                logger.warning("DiskWriter(%s): queue still full after %.0f s; abandoning it", self.run_dir, timeout)
                return
            self._thread.join(timeout)
            if self._thread.is_alive():
                logger.warning("DiskWriter(%s): writer still busy after %.0f s; abandoning it", self.run_dir, timeout)

    def lose(self, exc: OSError, what: str, amount: int, detail: str) -> None:
        """A stage could not write ``amount`` of ``what`` (``video bytes``): one drop, reported as the writer's own."""
        self._drop(_reason(exc), 1, detail, what, amount)

    def _drop(self, reason: str, count: int = 1, detail: str = "", what: str = "items", amount: int | None = None
              ) -> None:
        with self._lock:
            first = reason not in self.dropped
            self.dropped[reason] = self.dropped.get(reason, 0) + count
            if reason in DISK_ERRORS:
                self.lost[what] = self.lost.get(what, 0) + (count if amount is None else amount)
        if reason == "closed":
            return
        logger.debug("DiskWriter(%s): dropped %d (%s) %s", self.run_dir, count, reason, detail)
        if first and self._on_problem is not None:
            message = PROBLEMS.get(reason, reason) + (f": {detail}" if detail else "")
            self._on_problem(reason, message)

    def _image_done(self, nbytes: int) -> None:
        with self._lock:
            self._image_bytes_queued -= nbytes

    # -- writer thread ---------------------------------------------------------------------------

    def _run(self) -> None:
        tick_ns = 50_000_000
        next_flush = time.monotonic_ns() + int(self.flush_s * 1e9)
        next_tick = time.monotonic_ns() + tick_ns
        while True:
            now = time.monotonic_ns()
            try:
                item = self._queue.get(timeout=max(0.0, (min(next_flush, next_tick) - now) / 1e9))
            except queue.Empty:
                item = _IDLE
            if item is None:
                break
            if item is not _IDLE:
                self._handle(item)
            now = time.monotonic_ns()
            if now >= next_tick:
                for stage in self.stages:
                    self._collect(stage.due, now)
                next_tick = now + tick_ns
            if now >= next_flush:
                self._flush()
                self._free_bytes = self._disk_free()
                next_flush = now + int(self.flush_s * 1e9)
        for stage in self.stages:
            self._collect(stage.drain)
        self._flush()
        self._csv.close()

    def _handle(self, item: Any) -> None:
        try:
            if isinstance(item, Row):
                self._csv.add(item.table, item.values)
            elif isinstance(item, Rename):
                source = self.run_dir / item.source
                if source.exists():
                    os.replace(source, self.run_dir / item.target)
            elif isinstance(item, _Image):
                self._write_image(item)
            else:
                stage = next(stage for stage in self.stages if isinstance(item, stage.accepts))
                self._collect(stage.handle, item)
                self._collect(stage.due, time.monotonic_ns())
        except Exception as exc:  # noqa: BLE001 - the writer must outlive any bad item
            self._failed(type(item).__name__, exc)
        finally:
            if isinstance(item, Pixels):
                self._image_done(item.image.nbytes)

    def _collect(self, produce: Callable[..., Iterable[Row]], *args: Any) -> None:
        try:
            for row in produce(*args):
                self._csv.add(row.table, row.values)
        except Exception as exc:  # noqa: BLE001 - the writer must outlive a failing stage (a video write, say)
            self._failed(produce.__qualname__, exc)

    def _failed(self, what: str, exc: Exception) -> None:
        """``what`` could not be written: counted; a full disk is said once by its drop, and any other failure's
        traceback is logged the first time only (it would come again with every item)."""
        reason = _reason(exc)
        if reason == "write_error" and reason not in self.dropped:
            logger.error("DiskWriter(%s): cannot write %s (logged once)", self.run_dir, what, exc_info=exc)
        self._drop(reason, detail=f"{what}: {exc!r}")

    def _write_image(self, item: _Image) -> None:
        reason = self.image_refused()
        if reason is not None and reason != "closed":
            self._drop(reason)
            return
        image = item.image if item.image.dtype == np.uint8 else np.clip(item.image, 0, 255).astype(np.uint8)
        ok, encoded = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, self.jpeg_quality])
        if not ok:
            raise ValueError(f"cannot encode a {image.shape} {image.dtype} array as JPEG")
        path = self.run_dir / item.name
        temporary = path.with_name(path.name + ".tmp")
        data = encoded.tobytes()
        try:
            self._store(temporary, data)
            os.replace(temporary, path)
        except OSError as exc:
            temporary.unlink(missing_ok=True)
            self._drop(_reason(exc), detail=f"{item.name}: {exc}", what="frame images")
            return
        self.images_written += 1
        self.bytes_written += len(data)

    def _store(self, path: Path, data: bytes) -> None:
        """Write one whole file (the seam a throttled test writer overrides)."""
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(path, "wb") as handle:
            handle.write(data)

    def _flush(self) -> None:
        for table, rows in self._csv.take_pending():
            refused = self._space_refused()
            if refused is not None:
                self._drop(refused, len(rows), f"{table}.csv")
                continue
            try:
                self.bytes_written += self._csv.append(table, rows)
            except OSError as exc:
                self._drop(_reason(exc), len(rows), f"{table}.csv: {exc}", f"{table}.csv rows")

    def _write(self, fd: int, data: bytes) -> int:
        """One ``os.write`` (the seam a full-disk test writer overrides)."""
        return os.write(fd, data)

    def _disk_free(self) -> int:
        try:
            return shutil.disk_usage(self.run_dir).free
        except OSError:
            return 0


def _reason(exc: BaseException) -> str:
    """``disk_full`` for a disk (or quota) that is full, else ``write_error``."""
    return "disk_full" if isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, errno.EDQUOT) else "write_error"
