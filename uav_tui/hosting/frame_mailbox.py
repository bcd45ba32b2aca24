"""The newest frame, offered by the platform and claimed by the processor's process, in shared memory.

The platform *offers* every new frame (the name of the shared-memory slot it is in, its shape, capture
times and the telemetry attached to it) by overwriting the mailbox; the processor's process *claims* the
offer whenever it is ready for a frame. The hand-off needs no message and no help from the platform: a
busy processor finds the newest frame waiting the moment it is done, an idle one is woken by an eventfd.

Offer and claim are atomic under one lock (a Linux eventfd used as a semaphore, shared by both
processes), so when the platform replaces an offer it knows whether the processor took it (the slot is
then the processor's until it reports releasing it) or not (the platform lets the slot go at once).
A reader-paced replay waits for each claim (:meth:`FrameMailbox.wait_claimed`) to put its next frame while
the processor still works on this one; only then does the processor signal its claims (a third eventfd).
The eventfds and the shared memory are created by the platform, one set per process.
"""

from __future__ import annotations

import contextlib
import math
import mmap
import os
import select
import struct
import threading
import time
from multiprocessing.shared_memory import SharedMemory
from typing import NamedTuple

TELEMETRY_BYTES = 16 * 1024
"""Room for the encoded telemetry of one frame (a few hundred bytes in practice)."""

_CLAIM = struct.Struct("=qq")
"""Written by the processor: the gen it claimed last, and when (``time.monotonic_ns``, the same clock in both
processes)."""
_CLAIM_GEN = struct.Struct("=q")
"""The first field of ``_CLAIM`` alone: the gen claimed last."""
_WATCH = struct.Struct("=q")
"""Written by the platform: the gen whose claim it waits for (0: none), so the processor signals it."""
_WATCH_AT = _CLAIM.size
_NAME_BYTES = 64
_OFFER = struct.Struct(f"=qqqq iii {_NAME_BYTES}s d q I")
"""Written by the platform: gen, seq, t_mono_ns, t_wall_ns, shape (0 for no third axis), slot name, heartbeat
age (NaN for none), camera gen, telemetry length."""
_OFFER_AT = _WATCH_AT + _WATCH.size
_TELEMETRY_AT = _OFFER_AT + _OFFER.size
SIZE = _TELEMETRY_AT + TELEMETRY_BYTES
LOCK_TIMEOUT_S = 0.2
"""Longest wait for the lock: it is held for microseconds, so only a process killed holding it makes this run out."""


class Offer(NamedTuple):
    """One frame as the mailbox carries it (a named tuple: built on every frame, on both sides)."""

    gen: int
    """Offer number, from 1, increasing."""
    slot: str
    shape: tuple[int, ...]
    seq: int
    t_mono_ns: int
    t_wall_ns: int
    telemetry: bytes
    """The telemetry attached to the frame, MessagePack (the same bytes until the telemetry changes)."""
    heartbeat_age_s: float | None = None
    """The autopilot heartbeat's age at the offer (kept out of ``telemetry``: it changes every frame)."""
    camera_gen: int = 0
    """The :class:`~uav_tui.hosting.wire.Camera` message the frame is of (0: none was sent)."""


class MailboxGone(Exception):
    """The mailbox was closed, or its lock not released in time (the other process died holding it)."""


class SharedLock:
    """A lock two processes share: an eventfd used as a semaphore, 1 when free (``with lock:`` waits at most
    :data:`LOCK_TIMEOUT_S`). A class, not a generator context manager: it is taken several times a frame."""

    def __init__(self, fd: int, shm: SharedMemory | Segment) -> None:
        self.fd, self._shm = fd, shm

    def acquire(self, timeout_s: float = LOCK_TIMEOUT_S) -> None:
        """Raises MailboxGone when the mailbox is closed or the lock stays taken ``timeout_s``."""
        if self._shm.buf is None:
            raise MailboxGone("the frame mailbox is closed")
        deadline = None  # computed only when the lock is taken: the usual case costs one read
        while not self._try_take():
            now = time.monotonic()
            if deadline is None:
                deadline = now + timeout_s
            if now >= deadline:
                raise MailboxGone("the frame mailbox stayed locked: the other process died holding it")
            select.select([self.fd], [], [], deadline - now)

    def _try_take(self) -> bool:
        try:
            os.eventfd_read(self.fd)
        except BlockingIOError:
            return False
        return True

    def release(self) -> None:
        os.eventfd_write(self.fd, 1)

    def __enter__(self) -> None:
        self.acquire()

    def __exit__(self, *exc_info: object) -> None:
        self.release()


class FrameMailbox:
    """One side of the mailbox: the platform creates it (:meth:`create`), the processor attaches (:meth:`attach`)."""

    def __init__(self, shm: SharedMemory | Segment, lock_fd: int, wake_fd: int, claimed_fd: int, owner: bool) -> None:
        self._shm, self._owner = shm, owner
        self.lock_fd, self.wake_fd, self.claimed_fd = lock_fd, wake_fd, claimed_fd
        self._lock = SharedLock(lock_fd, shm)
        self._closing = False
        self._claimed_at_close = 0  # the processor's last claim, kept when the mapping goes
        self._waiters = 0  # threads in wait_claimed: close wakes them and lets them leave before the fds go
        self._waiters_left = threading.Condition()

    @classmethod
    def create(cls) -> FrameMailbox:
        shm = SharedMemory(create=True, size=SIZE)
        lock = os.eventfd(1, os.EFD_SEMAPHORE | os.EFD_NONBLOCK | os.EFD_CLOEXEC)
        wake, claimed = (os.eventfd(0, os.EFD_NONBLOCK | os.EFD_CLOEXEC) for _ in range(2))
        mailbox = cls(shm, lock, wake, claimed, owner=True)
        mailbox._buf[:_TELEMETRY_AT] = bytes(_TELEMETRY_AT)
        return mailbox

    @classmethod
    def attach(cls, address: str) -> FrameMailbox:
        """The processor's side, from what :attr:`address` said (the descriptors are inherited)."""
        name, lock, wake, claimed = address.split()
        return cls(Segment(name), int(lock), int(wake), int(claimed), owner=False)

    @property
    def address(self) -> str:
        """``"name lock_fd wake_fd claimed_fd"``: what the processor's process needs to attach."""
        return f"{self._shm.name} {self.lock_fd} {self.wake_fd} {self.claimed_fd}"

    @property
    def fds(self) -> tuple[int, int, int]:
        """The descriptors the processor's process inherits."""
        return self.lock_fd, self.wake_fd, self.claimed_fd

    @property
    def _buf(self) -> memoryview:
        """The mapped bytes; raises MailboxGone once unmapped."""
        if (buf := self._shm.buf) is None:
            raise MailboxGone("the frame mailbox is closed")
        return buf

    def fileno(self) -> int:
        """Readable when a frame was offered since :meth:`clear_wake` (for ``select``/``poll``)."""
        return self.wake_fd

    # -- the platform -----------------------------------------------------------------------------

    def offer(self, offer: Offer) -> tuple[int, bool]:
        """Replace the offer with ``offer``; returns the previous one's ``(gen, claimed)`` (gen 0: none).

        Raises MailboxGone when it was closed or the lock cannot be had (the processor died holding it),
        ValueError when the telemetry or the slot name does not fit.
        """
        name = offer.slot.encode()
        if len(offer.telemetry) > TELEMETRY_BYTES or len(name) > _NAME_BYTES:
            raise ValueError(f"offer does not fit: telemetry {len(offer.telemetry)} bytes (at most {TELEMETRY_BYTES}), "
                             f"slot name {len(name)} bytes (at most {_NAME_BYTES})")
        shape = (*offer.shape, 0)[:3]
        with self._lock:
            claimed = _CLAIM.unpack_from(self._buf)[0]
            gen = _OFFER.unpack_from(self._buf, _OFFER_AT)[0]
            _OFFER.pack_into(self._buf, _OFFER_AT, offer.gen, offer.seq, offer.t_mono_ns, offer.t_wall_ns,
                             *shape, name, math.nan if offer.heartbeat_age_s is None else offer.heartbeat_age_s,
                             offer.camera_gen, len(offer.telemetry))
            self._buf[_TELEMETRY_AT:_TELEMETRY_AT + len(offer.telemetry)] = offer.telemetry
        os.eventfd_write(self.wake_fd, 1)
        return gen, gen != 0 and claimed == gen

    def last_claim(self) -> tuple[int, int] | None:
        """``(gen, monotonic ns)`` of the processor's newest claim ((0, 0) before the first).

        Never waits: None when the lock is taken at this instant (or the mailbox is closed); ask again later.
        """
        try:
            self._lock.acquire(timeout_s=0)
        except MailboxGone:
            return None
        try:
            return _CLAIM.unpack_from(self._buf)
        finally:
            self._lock.release()

    def wait_claimed(self, gen: int, timeout_s: float) -> bool:
        """Block up to ``timeout_s`` until the processor claimed offer ``gen`` (or a later one); True once it has.

        Raises MailboxGone as :meth:`offer` does, and when another thread closes the mailbox meanwhile, unless
        the processor had claimed ``gen`` before (it died working on that frame: the frame was taken).
        """
        with self._waiters_left:
            if self._closing:
                return self._claimed_before_close(gen)
            self._waiters += 1
        try:
            # The usual case when decoding is the bottleneck, read without the lock (the mapping stays while a
            # waiter is counted): claims only grow and the gen is one aligned 8-byte word, so a read that races
            # a claim can only say "not yet", and the locked wait below asks again.
            claimed = _CLAIM_GEN.unpack_from(self._buf)[0] >= gen
            return claimed or self._await_claim(gen, time.monotonic() + timeout_s)
        finally:
            with self._waiters_left:
                self._waiters -= 1
                self._waiters_left.notify_all()

    def _await_claim(self, gen: int, deadline: float) -> bool:
        while True:
            with self._lock:
                claimed = _CLAIM.unpack_from(self._buf)[0]
                _WATCH.pack_into(self._buf, _WATCH_AT, 0 if claimed >= gen else gen)
            remaining = deadline - time.monotonic()
            if claimed >= gen or remaining <= 0:
                return claimed >= gen
            if select.select([self.claimed_fd], [], [], remaining)[0]:
                if self._closing:
                    return self._claimed_before_close(gen)
                _drain(self.claimed_fd)

    def _claimed_before_close(self, gen: int) -> bool:
        if self._claimed_at_close >= gen:
            return True
        raise MailboxGone("the frame mailbox was closed")

    # -- the processor ----------------------------------------------------------------------------

    def clear_wake(self) -> None:
        _drain(self.wake_fd)

    def claim(self) -> Offer | None:
        """Take the frame on offer, if there is one not taken yet."""
        with self._lock:
            claimed = _CLAIM.unpack_from(self._buf)[0]
            gen, seq, t_mono, t_wall, h, w, c, name, age, camera_gen, tel_len = _OFFER.unpack_from(self._buf,
                                                                                                    _OFFER_AT)
            if gen == 0 or claimed == gen:
                return None
            _CLAIM.pack_into(self._buf, 0, gen, time.monotonic_ns())
            watched = _WATCH.unpack_from(self._buf, _WATCH_AT)[0]
            if watched and gen >= watched:  # the watch is used up (a platform that finds a claim made without
                _WATCH.pack_into(self._buf, _WATCH_AT, 0)  # waiting for it never clears the watch itself)
            telemetry = bytes(self._buf[_TELEMETRY_AT:_TELEMETRY_AT + tel_len])
        if watched and gen >= watched:
            os.eventfd_write(self.claimed_fd, 1)
        shape = (h, w, c) if c else (h, w)
        return Offer(gen, name.rstrip(b"\0").decode(), shape, seq, t_mono, t_wall, telemetry,
                     None if math.isnan(age) else age, camera_gen)

    # -- both -------------------------------------------------------------------------------------

    def close(self) -> None:
        """Unmap (and, on the platform's side, unlink and close the descriptors). Idempotent.

        A thread in :meth:`wait_claimed` is woken first and has left before the descriptors are closed: it
        never waits on a closed one, nor reads one the process has meanwhile opened under the same number.
        """
        with self._waiters_left:
            if self._closing:
                return
            if self._owner:
                self._claimed_at_close = _CLAIM_GEN.unpack_from(self._buf)[0]
            self._closing = True
            if self._waiters:
                os.eventfd_write(self.claimed_fd, 1)
                self._waiters_left.wait_for(lambda: self._waiters == 0)
        self._shm.close()
        if self._owner and isinstance(self._shm, SharedMemory):  # the platform's side created the segment
            with contextlib.suppress(FileNotFoundError):
                self._shm.unlink()
            for fd in self.fds:
                os.close(fd)


def _drain(eventfd: int) -> None:
    with contextlib.suppress(BlockingIOError):
        os.eventfd_read(eventfd)


SHM_DIR = "/dev/shm"
"""Where Linux keeps POSIX shared memory (what ``shm_open`` opens)."""


class Segment:
    """A shared-memory segment the platform created, mapped by the processor's process: ``buf``, ``close``.

    Not :class:`~multiprocessing.shared_memory.SharedMemory`: attaching with it registers the segment with a
    resource tracker that unlinks it when this process ends (before Python 3.13), and it *unlinks the segment*
    when mapping fails, as it does once ``processor_memory_mb`` is reached: the platform's frame slot was gone,
    the next processor could not map it and the platform failed to unlink it at the stop. The platform owns
    every segment and unlinks it itself.
    """

    def __init__(self, name: str) -> None:
        fd = os.open(os.path.join(SHM_DIR, name.lstrip("/")), os.O_RDWR)
        try:
            self._mmap = mmap.mmap(fd, os.fstat(fd).st_size)
        finally:
            os.close(fd)
        self.name = name
        self.buf: memoryview | None = memoryview(self._mmap)
        """The mapped bytes; None once closed."""

    def close(self) -> None:
        """Unmap (raises BufferError while arrays made from ``buf`` are alive, as SharedMemory does). Idempotent."""
        if self.buf is not None:
            self.buf.release()
            self.buf = None
            self._mmap.close()

