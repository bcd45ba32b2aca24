"""The single-slot frame buffer between a capture thread and its readers."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, slots=True)
class Frame:
    """One captured image and when it was taken.

    Attributes:
        image: BGR uint8 array, H x W x 3. Readers must not assume they own it.
        seq: capture sequence number, 1 for the first frame of a source, rising by one per capture.
        t_mono_ns: ``time.monotonic_ns()`` at capture (system-wide on Linux, comparable across processes).
        t_wall_ns: ``time.time_ns()`` at capture.
    """

    image: np.ndarray
    seq: int
    t_mono_ns: int
    t_wall_ns: int

    @property
    def age_s(self) -> float:
        """Seconds since capture."""
        return (time.monotonic_ns() - self.t_mono_ns) / 1e9


class FrameBuffer:
    """Holds the newest frame only: a writer replaces it, readers never see a queue.

    ``put`` is called by the capture thread; ``latest`` and ``wait_newer`` by anyone.
    Listeners are called on the capture thread after each ``put`` and must only hand off
    (for example ``loop.call_soon_threadsafe(event.set)``).
    """

    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._frame: Frame | None = None
        self._read_seq = 0
        self._listeners: list[Callable[[Frame], None]] = []
        self.captured = 0
        """Frames put since creation."""
        self._taken = 0
        self._allocator: Callable[[tuple[int, ...]], np.ndarray | None] | None = None
        self._read_waiter: Callable[[int, float], bool] | None = None

    def put(self, image: np.ndarray, t_mono_ns: int | None = None, t_wall_ns: int | None = None) -> Frame:
        """Stamp ``image`` with the next sequence number and the capture times, and publish it.

        A source that knows when its image was taken better than "now" passes the times (a replay its
        recorded ones); given only the monotonic time, the wall time is derived from it.
        """
        t_mono, t_wall = time.monotonic_ns(), time.time_ns()
        if t_mono_ns is not None:
            t_mono, t_wall = t_mono_ns, t_wall_ns or t_wall - (t_mono - t_mono_ns)
        with self._cond:
            self.captured += 1
            frame = Frame(image, self.captured, t_mono, t_wall)
            self._frame = frame
            self._cond.notify_all()
            listeners = tuple(self._listeners)
        for listener in listeners:
            listener(frame)
        return frame

    @property
    def overwritten(self) -> int:
        """Frames replaced before any reader took them.

        A reader in another process may say it took a frame after a newer one came (:meth:`mark_read`);
        the count is right from then on.
        """
        with self._cond:
            newest_unread = self._frame is not None and self._frame.seq > self._read_seq
            return self.captured - newest_unread - self._taken

    @property
    def newest_seq(self) -> int:
        """Sequence number of the newest frame (0 before the first), without marking it read."""
        frame = self._frame
        return 0 if frame is None else frame.seq

    def peek(self) -> Frame | None:
        """The newest frame without marking it read (for watchdogs and status)."""
        return self._frame

    def wait_read(self, timeout: float) -> bool:
        """Block up to ``timeout`` s until a reader has taken the newest frame; True once it has.

        Lets a replaying source run in lockstep with its reader instead of decoding frames nobody takes.
        """
        waiter, frame = self._read_waiter, self._frame
        if waiter is not None and frame is not None and frame.seq > self._read_seq and waiter(frame.seq, timeout):
            self.mark_read(frame.seq)
            return True
        with self._cond:
            return self._cond.wait_for(lambda: self._frame is None or self._read_seq >= self._frame.seq,
                                       0 if waiter is not None else timeout)

    def latest(self) -> Frame | None:
        """The newest frame, or None before the first capture. Marks it as read."""
        with self._cond:
            if self._frame is not None:
                self._take(self._frame.seq)
            return self._frame

    def mark_read(self, seq: int) -> None:
        """Frame ``seq`` was taken by a reader that got it with :meth:`peek` (another process), maybe late."""
        with self._cond:
            self._take(seq)

    def wait_newer(self, seq: int, timeout: float) -> Frame | None:
        """Block up to ``timeout`` s for a frame newer than ``seq``; None if none came."""
        with self._cond:
            if not self._cond.wait_for(lambda: self._frame is not None and self._frame.seq > seq, timeout):
                return None
            assert self._frame is not None
            self._take(self._frame.seq)
            return self._frame

    def _take(self, seq: int) -> None:
        """Frame ``seq`` was taken by a reader (called holding the lock)."""
        if seq > self._read_seq:
            self._read_seq = seq
            self._taken += 1
            self._cond.notify_all()

    def set_read_waiter(self, waiter: Callable[[int, float], bool] | None) -> None:
        """Let :meth:`wait_read` ask the reader: ``waiter(seq, timeout)`` blocks until frame ``seq`` is taken (True)
        or ``timeout`` s passed (False). For a reader in another process that learns of a take before it can
        :meth:`mark_read` it; None: wait for ``mark_read``.
        """
        self._read_waiter = waiter

    def set_allocator(self, allocator: Callable[[tuple[int, ...]], np.ndarray | None] | None) -> None:
        """Let the reader provide the arrays frames are captured into (shared memory, say); None: the source's own."""
        self._allocator = allocator

    def new_image(self, shape: tuple[int, ...]) -> np.ndarray | None:
        """An array of ``shape`` for the next frame to be decoded into, or None (then the source allocates).

        Sources that can write into a given array (OpenCV's ``read(image)``) ask for one, so a reader
        that shares frames with another process gets them written once, in place.
        """
        allocator = self._allocator
        return allocator(shape) if allocator is not None else None

    def add_listener(self, listener: Callable[[Frame], None]) -> None:
        """Call ``listener(frame)`` on the capture thread after every put."""
        with self._cond:
            self._listeners.append(listener)

    def remove_listener(self, listener: Callable[[Frame], None]) -> None:
        """Stop calling ``listener``; unknown listeners are ignored."""
        with self._cond:
            if listener in self._listeners:
                self._listeners.remove(listener)
