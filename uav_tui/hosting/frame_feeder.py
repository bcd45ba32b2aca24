"""Frame feeding for the process host: the newest frame of a buffer, offered to the current child.

Frames live in :class:`~uav_tui.hosting.frame_ring.FrameRing`'s shared-memory slots (decoded there by cameras
that can; copied in once, off the capture thread, for those that cannot; never pickled). Every new frame
is *offered* in the child's :class:`~uav_tui.hosting.frame_mailbox.FrameMailbox`, replacing the previous offer,
and the child claims the newest whenever it is free: the hand-off waits for nothing in the platform.
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import logging
import threading
import time
from collections.abc import Iterable
from typing import TYPE_CHECKING

import numpy as np

from controllers.base import TELEMETRY_FIELDS
from sources.buffer import Frame, FrameBuffer
from uav_tui.events import EventLog
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.hosting.child_process import ChildProcess, Offered
from uav_tui.hosting.codec import PLAIN, camera_message
from uav_tui.hosting.frame_mailbox import TELEMETRY_BYTES, MailboxGone, Offer
from uav_tui.hosting.frame_ring import FrameRing
from uav_tui.hosting.wire import Forget, Result

if TYPE_CHECKING:
    from uav_tui.hosting.child_link import ChildLink
    from uav_values.camera import CameraModel

logger = logging.getLogger(__name__)


class FrameFeeder:
    """Offers the newest frame of a buffer to the current child, each frame once; takes the slots back.

    A frame captured into a slot is offered from whichever thread noticed it (no copy, no thread switch); one
    that must be copied is left to the feeder thread, off the capture thread, so the camera decodes its next
    frame meanwhile.

    Args:
        spec: the processor, for log lines.
        events: where a failing hand-off is reported (once).
        link: what sends a message to a child (:meth:`~uav_tui.hosting.child_link.ChildLink.send`).
    """

    def __init__(self, spec: str, events: EventLog, link: ChildLink) -> None:
        self.spec = spec
        self.events = events
        self.telemetry: TelemetryManager | None = None
        """Its telemetry at each frame's capture is attached to the frame."""
        self.child: ChildProcess | None = None
        """The child frames go to (None while there is none)."""
        self.hand_over_failures = 0
        """Frames that could not be handed to the child (a platform fault; the first is logged)."""
        self._link = link
        self._lock = threading.RLock()
        self._wake = threading.Condition(self._lock)
        self._offer_made = threading.Condition(self._lock)
        self._nudged = False
        self._starved = False
        """A frame found every slot held: the next slot freed nudges the feeder."""
        self._closing = False
        self._ring = FrameRing(on_free=self._on_slot_free, on_unlink=self._forget)
        self._to_forget: list[str] = []
        self._buffer: FrameBuffer | None = None
        self._camera: tuple[int, CameraModel | None] = (0, None)
        """The camera model of ``_buffer``'s source and its number (from 1; 0: none given), sent to each child
        (``tmMgr.camera()``) and named in each offer."""
        self._picked: tuple[FrameBuffer | None, int] = (None, 0)
        """The newest frame taken for an offer (each frame is offered once)."""
        self._offered: tuple[FrameBuffer | None, int, int] = (None, 0, 0)
        """The newest frame put in the mailbox, and its gen (an older frame is never put after it)."""
        self._encoded_telemetry: tuple[object, bytes] = (None, b"")
        """The newest telemetry update and its fields, encoded (MessagePack)."""
        self._gens = itertools.count(1)
        self._thread = threading.Thread(target=self._feed, name=f"processor-feeder({spec})", daemon=True)
        self._thread.start()

    @property
    def captured(self) -> int:
        """Frames captured by the attached buffer."""
        return self._buffer.captured if self._buffer is not None else 0

    def attach(self, buffer: FrameBuffer, camera: CameraModel | None = None) -> None:
        """Take frames from ``buffer`` from now on (a new source, with ``camera`` its model for ``tmMgr.camera()``)."""
        with self._lock:
            if self._buffer is not None:
                self._detach(self._buffer)
            self._buffer, self._camera, child = buffer, (self._camera[0] + 1, camera), self.child
            message = camera_message(*self._camera)
        if child is not None:
            self._link.send(child, message)  # its frames' offers name it: the child reads it before their first
        with self._lock:
            buffer.set_allocator(self._ring.capture_view)  # cameras that can decode into shared memory do
            buffer.set_read_waiter(functools.partial(self._wait_claimed, buffer))
            buffer.add_listener(self._on_frame)
        self._nudge()

    def feed(self, child: ChildProcess | None) -> None:
        """Offer frames to ``child`` from now on (None: to nobody); a new child is told the camera model first."""
        with self._lock:
            camera = self._camera
        if child is not None and camera[0]:
            self._link.send(child, camera_message(*camera))
        with self._lock:
            self.child = child
            self._picked, self._offered = (None, 0), (None, 0, 0)
        if child is not None:
            self._nudge()

    def take(self, child: ChildProcess, result: Result) -> Frame | None:
        """The frame ``result`` is for (its overlay in it), once the slots ``child`` let go are free again; None when
        it is not to be delivered (unknown, from a child no longer current, or the feeder is closing)."""
        with self._lock:
            offered = child.offered.pop(result.gen, None)
            # A copied-in frame's overlay is in the slot: lend it before the child's hold goes.
            slot_view = self._ring.lend(offered.slot) if offered is not None and offered.copied else None
        if offered is not None:
            offered.buffer.mark_read(offered.frame.seq)  # taken (a replay knew at the claim: _wait_claimed)
        self.release(child, result.released)
        if offered is None or child is not self.child or self._closing:
            return None
        frame = offered.frame
        if slot_view is not None:
            frame = Frame(slot_view, frame.seq, frame.t_mono_ns, frame.t_wall_ns)
        return frame

    def release(self, child: ChildProcess, names: Iterable[str]) -> None:
        """``child`` no longer references these slots."""
        with self._lock:
            slots = [child.held.pop(name) for name in names if name in child.held]
        for slot in slots:
            self._ring.release_child(slot)

    def retire(self, child: ChildProcess) -> None:
        """``child`` ended: nothing is on offer to it any more, and every slot it held is free."""
        with self._lock:
            child.offered.clear()
            child.mailbox.close()
        self.release(child, list(child.held))

    def stop(self) -> None:
        """Stop taking frames (the feeder thread ends)."""
        with self._wake:
            self._closing = True
            if self._buffer is not None:
                self._detach(self._buffer)
            self._wake.notify()

    def join(self, timeout: float) -> None:
        """After :meth:`stop`: wait for the feeder thread to leave (it may be copying a frame into a slot)."""
        self._thread.join(timeout)

    def close(self, children: list[ChildProcess]) -> None:
        """After :meth:`stop`: close the children's mailboxes and the ring."""
        with self._lock:  # no offer is being made: they check _closing under this lock
            for child in children:
                child.mailbox.close()
        self._ring.close()

    def _detach(self, buffer: FrameBuffer) -> None:
        buffer.remove_listener(self._on_frame)
        buffer.set_allocator(None)
        buffer.set_read_waiter(None)

    # -- offers (the feeder thread; anyone may nudge it) -----------------------------------------

    def _on_frame(self, frame: Frame) -> None:
        self._try_offer(may_copy=False)  # capture thread: a frame captured into a slot is offered at once

    def _nudge(self) -> None:
        """Wake the feeder: a frame to copy arrived, a starved frame found a free slot, a child started."""
        with self._wake:
            self._nudged = True
            self._wake.notify()

    def _on_slot_free(self) -> None:
        with self._lock:
            starved, self._starved = self._starved, False
        if starved:
            self._nudge()

    def _feed(self) -> None:
        """The feeder thread: copies the newest frame into a slot (when it was not captured into one) and offers it."""
        while True:
            with self._wake:
                self._wake.wait_for(lambda: self._nudged or self._closing)
                if self._closing:
                    return
                self._nudged = False
            self._try_offer(may_copy=True)

    def _try_offer(self, *, may_copy: bool) -> None:
        try:
            self._offer_newest(may_copy=may_copy)
        except Exception as exc:  # a bug here must not stop the camera: say so once, go on
            self.hand_over_failures += 1
            if self.hand_over_failures == 1:
                logger.exception("SubprocessHost(%s): handing a frame over failed (logged once)", self.spec)
                self.events.emit("error", "processor", f"frames cannot be handed to the processor: {exc!r}")

    def _offer_newest(self, *, may_copy: bool) -> None:
        """Offer the newest frame to the child, replacing the previous offer, if it was not offered yet; a frame that
        must be copied only when ``may_copy``."""
        with self._lock:
            child, buffer = self.child, self._buffer
            if self._closing or child is None or buffer is None or self._picked == (buffer, buffer.newest_seq):
                return
            frame = buffer.peek()  # read once the child claimed it (a replay then puts the next)
            if frame is None:
                return
            slot = self._ring.take_for_child(frame.image)
            copied = slot is None
            if copied and not may_copy:
                self._nudged = True
                self._wake.notify()
                return
            slot = slot or self._ring.acquire(frame.image.shape)
            if slot is None:
                self._starved = True  # every slot held: not picked; a newer frame or a freed slot tries again
                return
            self._picked = (buffer, frame.seq)
            forget, self._to_forget = self._to_forget, []
            camera_gen = self._camera[0]
        if copied:
            np.copyto(slot.array(), frame.image)  # the slot is ours alone until it is offered
        if forget:
            self._link.send(child, Forget(tuple(forget)))
        offer = Offer(next(self._gens), slot.name, slot.shape, frame.seq, frame.t_mono_ns, frame.t_wall_ns,
                      *self._telemetry_at(frame.t_mono_ns), camera_gen)
        with self._lock:
            current = child is self.child and not self._closing
            if current and self._offered[0] is buffer and self._offered[1] >= frame.seq:
                current = False  # a newer frame was offered while this one was copied
            if current:
                try:
                    previous, taken = child.mailbox.offer(offer)
                except MailboxGone:
                    current = False  # the child is gone: its exit is being reported
            if not current:
                unused = [slot]
            else:
                self._offered = (buffer, frame.seq, offer.gen)
                self._offer_made.notify_all()
                child.offered[offer.gen] = Offered(buffer, frame, slot, copied)
                child.held[slot.name] = slot
                replaced = None if taken else child.offered.pop(previous, None)
                unused = [child.held.pop(replaced.slot.name)] if replaced is not None else []
        for stale in unused:
            self._ring.release_child(stale)

    def _wait_claimed(self, buffer: FrameBuffer, seq: int, timeout_s: float) -> bool:
        """``buffer``'s read waiter: block until the child claimed frame ``seq`` (True) or ``timeout_s`` passed.

        A replay paced by its reader then puts its next frame while the child still works on this one.
        """
        deadline = time.monotonic() + timeout_s
        with self._offer_made:
            if not self._was_offered(buffer, seq) and not self._offer_made.wait_for(
                    lambda: self._was_offered(buffer, seq), timeout_s):
                return False
            child, gen = self.child, self._offered[2]
        if child is not None:
            with contextlib.suppress(MailboxGone):
                return child.mailbox.wait_claimed(gen, max(0.0, deadline - time.monotonic()))
        time.sleep(max(0.0, deadline - time.monotonic()))  # no child, or it died: its successor is offered the frame
        return False

    def _was_offered(self, buffer: FrameBuffer, seq: int) -> bool:
        return self._offered[0] is buffer and self._offered[1] >= seq

    def _telemetry_at(self, t_mono_ns: int) -> tuple[bytes, float | None]:
        """The telemetry attached to a frame: the newest update received by its capture encoded, the heartbeat age now.

        The update is encoded once, when it arrives; frames come faster than telemetry. Empty without a
        telemetry manager.
        """
        if self.telemetry is None:
            return b"", None
        latest, heartbeat_age = self.telemetry.at(t_mono_ns)
        if latest is not self._encoded_telemetry[0]:
            data = PLAIN.encode({name: getattr(latest, name) for name in TELEMETRY_FIELDS if name != "heartbeat_age_s"})
            if len(data) > TELEMETRY_BYTES:  # never seen: the fields are numbers and short names
                logger.warning("SubprocessHost: telemetry of %d bytes does not fit the frame mailbox; not attached",
                               len(data))
                data = b""
            self._encoded_telemetry = (latest, data)
        return self._encoded_telemetry[1], heartbeat_age

    def _forget(self, names: list[str]) -> None:
        self._to_forget.extend(names)
