"""The pipe between the platform and the processor's process: how a message is framed and read.

The child sends each :mod:`~uav_tui.hosting.wire` message with :func:`send_message`; the platform reads them with
:class:`Inbox` on the event loop, never blocking, and decodes them (:func:`uav_tui.hosting.codec.decode_from_child`).
The platform's own messages to the child are one frame each (:func:`send_to_child`), read with ``recv_bytes``.
"""

from __future__ import annotations

import os
import socket
import struct
from multiprocessing.connection import Connection

from uav_tui.hosting.codec import Encoder
from uav_tui.hosting.wire import FromChild, ToChild

BUFFER_COUNT = struct.Struct("!I")
"""Leads every frame that carries a message (:func:`send_message`): how many out-of-band frames follow it."""
MAX_BUFFERS = 64
"""The most out-of-band frames one message may have (a frame's ``tmMgr.save`` calls are throttled to a few)."""
MAX_FRAME_BYTES = 256 * 2**20
"""The longest frame a child may send: a saved 8K image is 100 MB. A longer one is never allocated."""


class PipeCorrupt(Exception):
    """A child wrote bytes that are not frames of messages (a length or count no sender makes): the pipe is read
    no further."""

_CHILD = Encoder(out_of_band=True)
_PLATFORM = Encoder(out_of_band=False)


def send_message(conn: Connection, message: FromChild) -> None:
    """Send ``message`` as one frame ``count + document`` then ``count`` frames with its arrays' bytes.

    Arrays (``tmMgr.save`` images) go out of band: written to the pipe straight from their memory, and the
    platform decodes them from the buffers it read, without copying them again.

    Raises:
        TypeError: a value in it is not data.
    """
    data, arrays = _CHILD.encode(message)
    conn.send_bytes(BUFFER_COUNT.pack(len(arrays)) + data)
    for array in arrays:
        conn.send_bytes(array.data.cast("B"))


def send_to_child(conn: Connection, message: ToChild) -> None:
    """Send one of the platform's messages (arrays inline: a camera model's, a few hundred bytes)."""
    conn.send_bytes(_PLATFORM.encode(message)[0])


class Inbox:
    """The child's messages, read without ever blocking: for the event loop, when the pipe is readable.

    The pipe is a socket (``multiprocessing.Pipe``); this reads a duplicate of it with ``MSG_DONTWAIT``
    (the platform's own sends stay blocking) and splits the bytes the way
    :class:`~multiprocessing.connection.Connection` framed them: a 4-byte big-endian length, or -1 and
    an 8-byte one for 2 GiB and more, then the bytes. A message is a frame with a document and the frames
    of its out-of-band buffers (:func:`send_message`); a frame longer than one read (an image from
    ``tmMgr.save``) is read straight into a buffer of its own size.

    Why not ``Connection.recv_bytes``: it cannot read without blocking, and the event loop must never
    block on a child. ``poll()`` says that *some* bytes arrived, and ``recv_bytes`` then waits for the
    whole message: a child that wrote a length and half a message (a multi-megabyte ``tmMgr.save`` image
    under way, or a child stopped or hung mid-write) would hold the loop until it wrote the rest, or
    forever (tried: ``recv_bytes`` after a 4-byte length and 500 of 1000 bytes had not returned after 1 s).
    Setting the descriptor non-blocking does not help: ``Connection._recv`` then raises
    ``BlockingIOError`` mid-message and drops the bytes it already read, so the next read takes payload
    bytes for a length (tried: the rest arriving afterwards could not be read). Reading whatever is
    there and keeping the partial frame here is what the loop needs.
    """

    CHUNK = 256 * 1024

    def __init__(self, conn: Connection) -> None:
        self._sock = socket.socket(fileno=os.dup(conn.fileno()))
        self._chunk = bytearray(self.CHUNK)
        self._pending = bytearray()
        self._long: bytearray | None = None
        """The long message being read, and how much of it has arrived (``_long_at``)."""
        self._long_at = 0
        self._message: tuple[memoryview, list[bytearray], int] | None = None
        """A document waiting for its out-of-band buffers: (document, buffers so far, how many)."""

    def fileno(self) -> int:
        return self._sock.fileno()

    def read(self) -> list[tuple[memoryview, list[bytearray]]] | None:
        """The messages completed by what has arrived, maybe none, as ``(document, buffers)`` for
        :func:`~uav_tui.hosting.codec.decode_from_child`; None at the end of the pipe.

        Raises:
            PipeCorrupt: the bytes are not frames of messages.
        """
        frames = self._frames()
        if frames is None:
            return None
        messages: list[tuple[memoryview, list[bytearray]]] = []
        for frame in frames:
            if self._message is None:
                if len(frame) < BUFFER_COUNT.size:
                    raise PipeCorrupt(f"a frame of {len(frame)} bytes has no message header")
                (count,), data = BUFFER_COUNT.unpack_from(frame), memoryview(frame)[BUFFER_COUNT.size:]
                if count > MAX_BUFFERS:
                    raise PipeCorrupt(f"a message with {count} out-of-band frames (at most {MAX_BUFFERS})")
                if count == 0:
                    messages.append((data, []))
                else:
                    self._message = (data, [], count)
                continue
            data, buffers, count = self._message
            buffers.append(frame)
            if len(buffers) == count:
                messages.append((data, buffers))
                self._message = None
        return messages

    def _frames(self) -> list[bytearray] | None:
        """The frames completed by what has arrived; None at the end of the pipe."""
        if self._long is not None:
            size = self._receive(memoryview(self._long)[self._long_at:])
            if size is None:
                return None
            self._long_at += size
            if self._long_at < len(self._long):
                return []
            frame, self._long = self._long, None
            return [frame]
        size = self._receive(memoryview(self._chunk))
        if size is None:
            return None
        self._pending += memoryview(self._chunk)[:size]
        return self._split()

    def _receive(self, into: memoryview) -> int | None:
        """Bytes read into ``into`` now (0 when none are there); None at the end of the pipe."""
        try:
            size = self._sock.recv_into(into, len(into), socket.MSG_DONTWAIT)
        except (BlockingIOError, InterruptedError):
            return 0
        except OSError:
            return None
        return size or None

    def _split(self) -> list[bytearray]:
        frames: list[bytearray] = []
        pending, at = self._pending, 0
        while len(pending) - at >= 4:
            (length,), start = struct.unpack_from("!i", pending, at), at + 4
            if length == -1:
                if len(pending) - at < 12:
                    break
                (length,), start = struct.unpack_from("!Q", pending, at + 4), at + 12
            if not 0 <= length <= MAX_FRAME_BYTES:
                raise PipeCorrupt(f"a frame of {length} bytes (at most {MAX_FRAME_BYTES})")
            if start + length > len(pending):
                if length > self.CHUNK:  # the rest goes straight into its own buffer
                    have = len(pending) - start
                    self._long = bytearray(length)
                    self._long[:have] = pending[start:]
                    self._long_at, at = have, len(pending)
                break
            frames.append(pending[start:start + length])
            at = start + length
        del pending[:at]
        return frames

    @property
    def closed(self) -> bool:
        return self._sock.fileno() < 0

    def close(self) -> None:
        self._sock.close()
