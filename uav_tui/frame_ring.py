"""The shared-memory frame slots between the platform and a processor's process.

Ownership. A slot is free or held; it is written only while free, so nobody ever sees it change under
them. Holds are counted, and a slot goes back to the free list when the count reaches zero:

- ``acquire`` hands a free slot to the capture side, which copies the newest frame into it once and
  sends it to the processor's process: that is the **child's hold**. The child draws its overlay into
  the slot; ``release_child`` drops the hold when the child reports it no longer references the frame
  (usually right after the frame; later if the researcher kept the array, e.g. the previous frame).
- ``lend`` gives the platform a NumPy view for the frame's :class:`ProcessedFrame`: the **view's hold**,
  dropped by a finalizer when the last reference to that view (or any array derived from it) is gone.
  So the preview, the recorder's queue and the web encoder may keep ``result.frame.image`` as long as
  they need: the slot is not reused before they let go, and nobody has to remember to release it.

When readers keep many frames the ring grows, up to ``max_slots``. Before it runs dry, ``lend`` hands
out a private copy instead of a view (``copied`` counts them), so a reader that keeps every frame costs
memory, as it would with the thread worker, but never stops the pipeline; if the child itself keeps
frames and every slot is held, the capture side skips frames until one is free (``starved``). A slot
of another size (the camera changed) is never reused: free slots of the old size are unlinked.
"""

from __future__ import annotations

import threading
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.shared_memory import SharedMemory

import numpy as np

MAX_SLOTS = 8
"""One in the child, one being written, the rest held by readers (preview, web, recorder, snapshot)."""
RESERVE = 2
"""Slots ``lend`` keeps available for the frames to come; below that it copies."""


@dataclass(eq=False)
class Slot:
    shm: SharedMemory
    shape: tuple[int, ...]
    holds: int = 0

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
        self.starved = 0
        """Frames skipped because every slot was held."""
        self.copied = 0
        """Frames lent as private copies because readers held too many slots."""
        self._slots: list[Slot] = []
        self._lock = threading.RLock()
        self._on_free = on_free
        self._on_unlink = on_unlink
        self._closed = False

    def acquire(self, shape: tuple[int, ...]) -> Slot | None:
        """A free slot of ``shape`` with the child's hold taken, or None when every slot is held."""
        with self._lock:
            stale = [s for s in self._slots if s.holds == 0 and s.shape != shape]
            if stale:
                self._unlink(stale)
            slot = next((s for s in self._slots if s.holds == 0), None)
            if slot is None and len(self._slots) < self.max_slots and not self._closed:
                slot = Slot(SharedMemory(create=True, size=int(np.prod(shape))), shape)
                self._slots.append(slot)
            if slot is None:
                self.starved += 1
                return None
            slot.holds = 1
            return slot

    def lend(self, slot: Slot) -> np.ndarray:
        """A view of ``slot`` that holds it until the view and every array made from it are gone.

        A private copy instead when fewer than :data:`RESERVE` slots would be left for new frames.
        """
        with self._lock:
            available = sum(s.holds == 0 for s in self._slots) + self.max_slots - len(self._slots)
            if available < RESERVE:
                self.copied += 1
                return slot.array().copy()
            slot.holds += 1
        view = slot.array()
        weakref.finalize(view, self._drop, slot)
        return view

    def release_child(self, slot: Slot) -> None:
        """The child no longer references ``slot`` (or died)."""
        self._drop(slot)

    def find(self, name: str) -> Slot | None:
        with self._lock:
            return next((s for s in self._slots if s.name == name), None)

    @property
    def size(self) -> int:
        return len(self._slots)

    def close(self) -> None:
        """Unlink every slot now (views still held stay valid); each is unmapped when its last hold goes."""
        with self._lock:
            self._closed = True
            self._unlink(self._slots[:])

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
        for slot in slots:
            self._slots.remove(slot)
            slot.shm.unlink()
            if slot.holds == 0:
                slot.shm.close()
        self._on_unlink([s.name for s in slots])
