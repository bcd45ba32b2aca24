"""``self.tmMgr``: the telemetry and the clock of the frame being processed, and ``save``; the same in every host.

Every host (a platform thread, the processor's own process, a replay, ``uav-tui eval``) gives the processor a
:class:`FrameTelemetry` and calls :meth:`FrameTelemetry.begin` before each ``photo_processing`` with the frame's
capture number and time and the telemetry at its capture. So ``snapshot()`` means one thing everywhere, and a
processor that paces itself by ``snapshot().frame_t_ns`` (never by ``time.monotonic()``) does the same on a
replay at any speed, and on ``eval``, as in flight.

``save(frame, **extra)`` hands the image and the fields to the host's store (the recorder; in eval the output
folder) at most ``save_max_hz`` times a second of the frames' time; more calls are dropped (counted in
``saves_throttled``; eval's table shows it) with one warning, once they have gone on for a second of frame time,
that says how much disk saving them all would fill in an hour.

``camera()`` is the source's camera model (:class:`uav_values.camera.CameraModel`: intrinsics and mounting), or
None when there is none (no calibration file or field of view configured; eval's annotated video): the host sets it
whenever the source changes.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from uav_values.telemetry import TELEMETRY_FIELDS, Snapshot

if TYPE_CHECKING:
    from uav_values.camera import CameraModel

logger = logging.getLogger(__name__)

DEFAULT_SAVE_MAX_HZ = 5.0
"""Saves stored per second of frame time unless configured (``save_max_hz``): a JPEG of a 640x480 frame is
about 60 kB, so 5 a second fill about 1 GB an hour (position hold's fast mode estimates, and saves, 5 a second)."""
JPEG_BYTES_PER_PIXEL = 0.19
"""About 1.5 bits a pixel: a quality-90 JPEG of aerial video (the estimate of the throttle's warning)."""

_FIELDS = frozenset(TELEMETRY_FIELDS) - {"heartbeat_age_s"}

Store = Callable[[np.ndarray, dict[str, Any]], None]
"""``store(image, extra)``: what the host does with one save; it copies the pixels it keeps (the processor may
draw on the array after the call)."""


@runtime_checkable
class _HasImage(Protocol):
    """A frame object that carries its pixels (``sources.buffer.Frame``), saved as its ``image``."""

    image: object


class FrameTelemetry:
    """What a processor sees as ``self.tmMgr``: ``snapshot()``, ``link_alive()``, ``save(frame, **extra)``,
    ``camera()``.

    Args:
        store: called with each save that is not dropped.
        save_max_hz: saves stored per second of frame time (bursts of up to ``max(1, save_max_hz)``); 0 for no
            limit.
    """

    def __init__(self, store: Store, *, save_max_hz: float = DEFAULT_SAVE_MAX_HZ) -> None:
        self.store = store
        self.save_max_hz = save_max_hz
        self.saves = 0
        """Saves handed to the store."""
        self.saves_throttled = 0
        """Saves dropped for coming faster than ``save_max_hz``."""
        self.current = Snapshot()
        self.camera_model: CameraModel | None = None
        """Set by the host: the model of the source the frames come from."""
        self._tokens = 0.0
        self._refilled_ns: int | None = None
        self._first_call: tuple[int, int] | None = None
        """(frame_t_ns of the first save call, calls since): the attempted rate the warning states."""
        self._warned = False

    def begin(self, seq: int, t_ns: int, t_wall_ns: int, telemetry: Mapping[str, Any],
              heartbeat_age_s: float | None) -> None:
        """The host, before ``photo_processing``: the frame's number, capture times and the telemetry at capture
        (fields of :class:`~uav_values.telemetry.Telemetry`; any other key is not telemetry and is left out)."""
        known = {name: value for name, value in telemetry.items() if name in _FIELDS}
        self.current = Snapshot(**known, heartbeat_age_s=heartbeat_age_s, frame_seq=seq, frame_t_ns=t_ns,
                                frame_t_wall_ns=t_wall_ns)

    def snapshot(self) -> Snapshot:
        """The telemetry at the capture of the frame being processed, with its ``frame_seq`` and ``frame_t_ns``."""
        return self.current

    def camera(self) -> CameraModel | None:
        """The camera model of the frames (pixel <-> ray, intrinsics, mounting); None: no camera model is known."""
        return self.camera_model

    def link_alive(self, max_age_s: float = 1.5) -> bool:
        """True when the autopilot's heartbeat was younger than ``max_age_s`` when the frame was handed over."""
        age = self.current.heartbeat_age_s
        return age is not None and age < max_age_s

    def save(self, frame: Any, **extra: Any) -> None:
        """Store ``frame`` with the telemetry of its capture and ``extra`` columns (dropped above ``save_max_hz``)."""
        image = frame.image if isinstance(frame, _HasImage) else frame
        if not isinstance(image, np.ndarray) or image.ndim not in (2, 3):
            raise TypeError(f"tmMgr.save(frame, **extra): frame must be an image array, got {type(image).__name__}")
        if not self._take_token(image):
            return
        self.saves += 1
        self.store(image, extra)

    def _take_token(self, image: np.ndarray) -> bool:
        if self.save_max_hz <= 0:
            return True
        now = self.current.frame_t_ns
        first, calls = self._first_call or (now, 0)
        self._first_call = (first, calls + 1)
        burst = max(1.0, self.save_max_hz)
        if self._refilled_ns is None:
            self._tokens = burst
        else:
            self._tokens = min(burst, self._tokens + max(0, now - self._refilled_ns) / 1e9 * self.save_max_hz)
        self._refilled_ns = now
        if self._tokens >= 1.0:
            self._tokens -= 1.0
            return True
        self.saves_throttled += 1
        if not self._warned and now - first >= 1e9:
            self._warned = True
            rate = calls / ((now - first) / 1e9)  # calls before this one, over the time since the first
            gb_per_hour = rate * 3600 * image.shape[0] * image.shape[1] * JPEG_BYTES_PER_PIXEL / 1e9
            logger.warning("tmMgr.save is called %.0f times a second (%dx%d frames): storing them all would fill about "
                           "%.1f GB an hour; storing at most %g a second (save_max_hz in [recording]), the others "
                           "are dropped", rate, image.shape[1], image.shape[0], gb_per_hour, self.save_max_hz)
        return False


def frame_time_s(tm_mgr: Any) -> float:
    """The capture time (s) of the frame being processed, from ``tm_mgr.snapshot().frame_t_ns``: pace by this.

    Outside a host (a processor called directly, a ``tmMgr`` of None or without a frame clock) there is no
    frame clock, and this is ``time.monotonic()``.
    """
    snapshot = tm_mgr.snapshot() if tm_mgr is not None else None
    return snapshot.frame_t_s if isinstance(snapshot, Snapshot) else time.monotonic()
