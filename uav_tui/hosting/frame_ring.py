"""The shared-memory frame slots between the platform and a processor's process.

Ownership. A slot is free or held; it is written only while free, so nobody ever sees it change under
them. Holds are counted, and a slot goes back to the free list when the count reaches zero:

- ``capture_view`` gives a camera a free slot to decode into (through ``FrameBuffer``'s allocator), so
  the frame is written once, in shared memory. That view holds the slot for as long as it lives (a
  **view's hold**, dropped by a finalizer when the last reference to the view, or to any array made
  from it, is gone): the buffer, the preview, the recorder's queue and the web encoder may keep
  ``frame.image`` as long as they need, and nobody has to remember to release it.
- Handing a frame to the child adds the **child's hold**: ``take_for_child`` for a frame captured into
  a slot (no copy); ``acquire`` for a frame of the camera's own (a free slot, the frame copied in
  once). The child draws its overlay into the slot; ``release_child`` drops the hold when the child
  reports it no longer references the frame (right after it, or later if the researcher kept it).
- ``lend`` gives a copied-in slot's view to the frame's ``ProcessedFrame`` (a view's hold again).

When readers keep many frames the ring grows, up to ``max_slots``. Before it runs dry, ``lend`` hands
out a private copy instead of a view, so a reader that keeps every frame costs
memory, as it would with the thread worker, but never stops the pipeline; if the child itself keeps
frames and every slot is held, the capture side skips frames until one is free. A slot
of another size (the camera changed) is never reused: free slots of the old size are unlinked.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
import weakref
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from multiprocessing import resource_tracker
from multiprocessing.shared_memory import SharedMemory

import numpy as np

from uav_tui.hosting.child import JOB_SIGNALS

MAX_SLOTS = 12
"""One in the child, one being written, the rest held by readers (preview, web, recorder, snapshot)."""
RESERVE = 2
"""Slots ``lend`` keeps available for the frames to come; below that it copies."""


@dataclass(eq=False)
class Slot:
    shm: SharedMemory
    shape: tuple[int, ...]
    holds: int = 0
    mapping: object = field(init=False)
    """What the slot's arrays are views of (their ``base``): how a frame decoded into the slot is recognised."""

    def __post_init__(self) -> None:
        self.mapping = self.array().base

    @property
    def name(self) -> str:
        return self.shm.name

    def array(self) -> np.ndarray:
        return np.ndarray(self.shape, dtype=np.uint8, buffer=self.shm.buf)


class FrameRing:
    """Shared-memory slots for frames, reused only when nobody holds them. Thread-safe.

    Args:
        on_free: called (on whichever thread let go) when a slot becomes free, to resume a starved sender.
        on_unlink: called with the names of slots that were unlinked (the child unmaps them).
    """

    def __init__(self, *, max_slots: int = MAX_SLOTS, on_free: Callable[[], None] = lambda: None,
                 on_unlink: Callable[[list[str]], None] = lambda names: None) -> None:
        self.max_slots = max_slots
        self._slots: list[Slot] = []
        self._lock = threading.RLock()
        self._on_free = on_free
        self._on_unlink = on_unlink
        self._closed = False

    def capture_view(self, shape: tuple[int, ...]) -> np.ndarray | None:
        """A free slot as an array for a camera to decode into (``FrameBuffer`` allocator), or None.

        The view holds the slot (as :meth:`lend`'s do), so the frame that carries it keeps its pixels
        until every reader let go. None when only :data:`RESERVE` slots are left: the camera then
        allocates its own array and the frame is copied into a slot when it is handed over.
        """
        with self._lock:
            slot = self._take_free(shape, keep=RESERVE)
            if slot is None:
                return None
        return self._view(slot)

    def take_for_child(self, image: np.ndarray) -> Slot | None:
        """The slot ``image`` was captured into, with the child's hold taken; None if it is not one of ours."""
        mapping = image.base
        with self._lock:
            slot = next((s for s in self._slots if s.mapping is mapping and s.shape == image.shape), None)
            if slot is not None:
                slot.holds += 1
            return slot

    def acquire(self, shape: tuple[int, ...]) -> Slot | None:
        """A free slot of ``shape`` with the child's hold taken (the frame is copied in), or None."""
        with self._lock:
            return self._take_free(shape, keep=0)

    def lend(self, slot: Slot) -> np.ndarray:
        """A view of ``slot`` that holds it until the view and every array made from it are gone.

        A private copy instead when fewer than :data:`RESERVE` slots would be left for new frames.
        """
        with self._lock:
            if self._available() < RESERVE:
                return slot.array().copy()
            slot.holds += 1
        return self._view(slot)

    def release_child(self, slot: Slot) -> None:
        """The child no longer references ``slot`` (or died)."""
        self._drop(slot)

    def close(self) -> None:
        """Unlink every slot now (views still held stay valid); each is unmapped when its last hold goes."""
        with self._lock:
            self._closed = True
            self._unlink(self._slots[:])

    def _available(self) -> int:
        return sum(s.holds == 0 for s in self._slots) + self.max_slots - len(self._slots)

    def _take_free(self, shape: tuple[int, ...], keep: int) -> Slot | None:
        """A free slot of ``shape`` (created if there is room) with one hold, leaving ``keep`` available."""
        stale = [s for s in self._slots if s.holds == 0 and s.shape != shape]
        if stale:
            self._unlink(stale)
        if self._closed or self._available() <= keep:
            return None
        slot = next((s for s in self._slots if s.holds == 0), None)
        if slot is None:
            ensure_resource_tracker()
            slot = Slot(SharedMemory(create=True, size=int(np.prod(shape))), shape)
            self._slots.append(slot)
        slot.holds = 1
        return slot

    def _view(self, slot: Slot) -> np.ndarray:
        """A view of ``slot`` whose finalizer drops one hold (taken by the caller).

        The finalizer refers to the ring weakly: finalizers are kept by a global registry, and a view
        kept by the ring's owner (its last frame) would otherwise keep the owner, its pipes and every
        slot alive for good once it is closed.
        """
        view = slot.array()
        weakref.finalize(view, _drop_view_hold, weakref.ref(self), slot)
        return view

    def _drop(self, slot: Slot) -> None:
        with self._lock:
            slot.holds -= 1
            if slot.holds > 0:
                return
            if self._closed:
                slot.shm.close()
                return
        self._on_free()

    def _unlink(self, slots: list[Slot]) -> None:
        """Remove ``slots`` from the ring and the system; unmap those nobody holds."""
        if slots:
            ensure_resource_tracker()
        for slot in slots:
            self._slots.remove(slot)
            with contextlib.suppress(FileNotFoundError):  # gone already: a processor's code may unlink /dev/shm files
                slot.shm.unlink()
            if slot.holds == 0:
                slot.shm.close()
        self._on_unlink([s.name for s in slots])


def _drop_view_hold(ring: weakref.ref[FrameRing], slot: Slot) -> None:
    """A view of ``slot`` is gone: drop its hold. Without the ring (collected) there is nothing to drop: the slot's
    memory is unmapped as the last view's finalizer, the last reference to the slot, goes."""
    if (alive := ring()) is not None:
        alive._drop(slot)


def ensure_resource_tracker() -> None:
    """Start multiprocessing's resource tracker (it unlinks shared memory if this process is killed), or
    start it again if it died. Call before creating or unlinking shared memory.

    - SharedMemory would start it with ``sys.stderr``'s descriptor; under the dashboard, Textual has
      replaced ``sys.stderr`` with an object that has none (``bad value(s) in fds_to_keep``): give it the
      real one.
    - It shares the terminal's job, and a hang-up or a Ctrl-Z is sent to every process of the job: it
      starts with the job's signals blocked (the mask is inherited, and it never unblocks them), so it
      outlives the terminal and is never left stopped by a Ctrl-Z that the platform itself ignores.
    """
    with job_signals_blocked(), contextlib.redirect_stderr(sys.__stderr__ or sys.stderr):
        resource_tracker.ensure_running()


@contextlib.contextmanager
def job_signals_blocked() -> Iterator[None]:
    """Block the terminal's job signals in this thread while it starts a process, which inherits the mask.

    Between fork and exec the new process has default handlers: a Ctrl-Z sent to the job then stops it before
    it runs its program, and this process waits for it in the kernel (vfork, unkillable) until ``fg``: the
    vehicle was no longer flown. Ctrl-C would kill it before it ran.
    """
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, JOB_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)
