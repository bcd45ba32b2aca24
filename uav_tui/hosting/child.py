"""The processor's own process: ``python -m uav_tui.hosting.child FD MAILBOX`` runs one processor behind a pipe.

The platform (``uav_tui.hosting.process_host``) starts this module in a fresh interpreter and talks to it
over the :class:`~multiprocessing.connection.Connection` on file descriptor ``FD``; frames come through
the :class:`~uav_tui.hosting.frame_mailbox.FrameMailbox` at ``MAILBOX`` (its address, one argument). It imports only
the ``processors`` level, its own few modules here
(``tests/test_layering.py`` lists them), NumPy and the researcher's code: a GIL-bound loop, a hang, ``os._exit``,
a segfault or a leak here cannot freeze or kill the flight path.

The messages both ways are :mod:`uav_tui.hosting.wire`'s. Frames are not messages: whenever it is free (no
call waiting), this process claims the frame on offer in the mailbox (the image in a shared-memory slot, read
and drawn in place, and the telemetry attached to it, MessagePack) and answers with a ``Result`` for that offer's
``gen``.

``saves`` are the ``tmMgr.save(frame, **extra)`` calls made meanwhile: ``(image, extra)``, the image
copied at the call (what is drawn afterwards must not reach the dataset), so it is sent. When the
platform does not record (``save_images`` false) the image is None: nothing is copied or sent for it.
``tmMgr`` is a :class:`~processors.frame_telemetry.FrameTelemetry`: its snapshot is the offer's seq and capture
times with the telemetry attached to it; saves beyond ``save_max_hz`` are dropped here, before any copy.
The processor's log records go to stderr one per line, as ``LOG_TAG level name "json text"``, so the
platform logs them as its own (escaped and redacted like every record); anything else the process
prints is forwarded line by line, escaped.

``released`` names the slots this process no longer references (see ``Result.released``). What crosses is data only
(:mod:`uav_tui.hosting.codec`): a returned value that is not data is sent as its ``repr`` (a vector, a save's
``extra``, a call's answer) or makes the frame's outputs its error.

Calls and frames run one at a time in this process's main thread (calls first), so a researcher never
needs a lock.
A ``MemoryError`` (``processor_memory_mb`` reached) ends the process with :data:`MEMORY_EXIT_CODE`.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import faulthandler
import json
import logging
import os
import resource
import select
import signal
import sys
import time
import traceback
import weakref
from collections.abc import Iterator
from multiprocessing import resource_tracker
from multiprocessing.connection import Connection
from typing import Any

import msgspec
import numpy as np

from processors import load_processor
from processors.errors import ProcessorLoadError
from processors.frame_telemetry import DEFAULT_SAVE_MAX_HZ, FrameTelemetry
from processors.outputs import NO_OUTPUTS, output_methods
from uav_tui.hosting.codec import TO_CHILD, as_data, camera_model
from uav_tui.hosting.frame_call import call_frame
from uav_tui.hosting.frame_mailbox import FrameMailbox, Offer, Segment
from uav_tui.hosting.pipe import send_message
from uav_tui.hosting.tracks import DetectionTracks
from uav_tui.hosting.wire import Call, Camera, Forget, Load, LoadError, Ready, Reply, Result, Save, ToChild

JOB_SIGNALS = frozenset({signal.SIGINT, signal.SIGQUIT, signal.SIGHUP, signal.SIGTSTP, signal.SIGTTIN, signal.SIGTTOU})
"""What a terminal sends to every process of its job. The platform starts this process with them blocked (a
process between fork and exec has default handlers: a Ctrl-Z then stops it, and the platform with it, in the
kernel's vfork wait); what came meanwhile is discarded here, then they are unblocked."""

LOG_LEVEL_ENV = "UAV_TUI_PROCESSOR_LOG_LEVEL"
"""The platform's log level, for the child's root logger."""

MEMORY_EXIT_CODE = 86
"""Exit status after a MemoryError: the ``processor_memory_mb`` cap was reached."""

LOG_TAG = "\x00uav-tui-log\t"
"""Starts a stderr line that carries one log record: ``LOG_TAG + f"{levelno}\\t{name}\\t{json text}"``."""

_PR_SET_PDEATHSIG = 1


class TaggedLogHandler(logging.Handler):
    """Writes each log record on one tagged stderr line, for the platform to log it as its own."""

    def emit(self, record: logging.LogRecord) -> None:
        try:
            text = json.dumps(self.format(record))
            sys.stderr.write(f"{LOG_TAG}{record.levelno}\t{record.name}\t{text}\n")
            sys.stderr.flush()
        except Exception:  # noqa: BLE001 - logging must never break the processor
            self.handleError(record)


def parse_log_line(line: str) -> tuple[int, str, str] | None:
    """``(levelno, logger name, text)`` of a tagged stderr line, or None for any other line."""
    if not line.startswith(LOG_TAG):
        return None
    try:
        level, name, text = line[len(LOG_TAG):].split("\t", 2)
        return int(level), name, str(json.loads(text))
    except ValueError:
        return None


class Slots:
    """The shared-memory slots this process has mapped, and which of its frame views are still alive."""

    def __init__(self) -> None:
        self._mapped: dict[str, Segment] = {}
        self._alive: dict[str, weakref.ref[np.ndarray]] = {}

    def view(self, name: str, shape: tuple[int, ...]) -> np.ndarray:
        shm = self._mapped.get(name) or self._attach(name)
        array = np.ndarray(shape, dtype=np.uint8, buffer=shm.buf)
        self._alive[name] = weakref.ref(array)
        return array

    def released(self) -> list[str]:
        """Slots no view of which is referenced any more (each reported once)."""
        gone = [name for name, ref in self._alive.items() if ref() is None]
        for name in gone:
            del self._alive[name]
        return gone

    def forget(self, names: tuple[str, ...]) -> None:
        for name in names:
            shm = self._mapped.pop(name, None)
            if shm is not None and name not in self._alive:
                shm.close()

    def _attach(self, name: str) -> Segment:
        try:
            shm = self._mapped[name] = Segment(name)
        except OSError as exc:
            if exc.errno == errno.ENOMEM:  # the address space is full: processor_memory_mb was reached
                raise MemoryError(f"cannot map the frame ({exc.strerror})") from exc
            raise
        return shm


def _limit_memory(memory_mb: float | None) -> str:
    """Cap this process's address space at ``memory_mb``; or, when that is no more than it already uses (nothing
    could be loaded), leave it and return why ("" when capped or no cap)."""
    if memory_mb:
        limit = int(memory_mb * 1024 * 1024)
        with open("/proc/self/statm") as statm:
            used = int(statm.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
        if limit <= used:
            return (f"processor_memory_mb = {memory_mb:g} MB is too small: the processor's process already uses "
                    f"{used / 2**20:.0f} MB of address space before loading the processor; set processor_memory_mb "
                    "(uav.toml, or --processor-memory-mb) well above that, or 0 for no cap")
        _, hard = resource.getrlimit(resource.RLIMIT_AS)
        resource.setrlimit(resource.RLIMIT_AS, (limit, hard if hard != resource.RLIM_INFINITY else limit))
    return ""


def _start_resource_tracker() -> None:
    """Start multiprocessing's resource tracker in the platform's process group, not this process's.

    The tracker unlinks the shared memory and semaphores this process, and those it starts, leave behind
    once they have all ended; the platform kills this process's whole group, and the tracker must outlive it.
    Meanwhile this process is in the platform's (the terminal's) group: terminal signals are ignored, and
    the tracker keeps ignoring them, so a hang-up does not end it before it has cleaned up. Its output goes
    to /dev/null, not to this process's pipe: the platform's reader of that pipe would wait for it to end.
    """
    own_group, platform_group = os.getpgid(0), os.getpgid(os.getppid())
    ignored = {sig: signal.signal(sig, signal.SIG_IGN) for sig in JOB_SIGNALS}  # drops those sent while starting
    try:
        os.setpgid(0, platform_group)
        with _output_to_devnull():
            resource_tracker.ensure_running()
        os.setpgid(0, own_group)
    finally:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, JOB_SIGNALS)  # blocked by the platform while it started this
        for sig, handler in ignored.items():
            signal.signal(sig, handler)


@contextlib.contextmanager
def _output_to_devnull() -> Iterator[None]:
    """Descriptors 1 and 2 on /dev/null meanwhile: what is started now inherits that instead."""
    saved = [os.dup(fd) for fd in (1, 2)]
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        for fd in (1, 2):
            os.dup2(devnull, fd)
        yield
    finally:
        for fd, copy in zip((1, 2), saved, strict=True):
            os.dup2(copy, fd)
            os.close(copy)
        os.close(devnull)


def _die_with_parent() -> None:
    """Linux: be killed when the platform dies, whatever this process is doing."""
    with contextlib.suppress(OSError, AttributeError):  # not Linux
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)


class ChildRunner:
    """Serves one processor: calls as they arrive, the newest frame whenever no call waits; one at a time."""

    def __init__(self, conn: Connection, mailbox: FrameMailbox, loaded: Any, *, save_images: bool = True,
                 save_max_hz: float = DEFAULT_SAVE_MAX_HZ, first_track_id: int = 0) -> None:
        self.conn = conn
        self.mailbox = mailbox
        self.loaded = loaded
        self.instance = loaded.instance
        self.saves: list[Save] = []
        """The ``tmMgr.save`` calls since the last message (sent with the next result or reply)."""
        self.save_images = save_images
        self.telemetry = FrameTelemetry(self._keep_save, save_max_hz=save_max_hz)
        self._throttled_sent = 0
        self.instance.tmMgr = self.telemetry
        self.slots = Slots()
        self.has_vector = "getPreparedVector" in loaded.info.capabilities
        self.outputs = output_methods(loaded.info.capabilities)
        self.tracks = DetectionTracks(first_track_id)
        self.camera_gen = 0
        """The number of the last :class:`~uav_tui.hosting.wire.Camera` message read."""
        self._telemetry: tuple[bytes, dict[str, Any]] = (b"", {})
        """The last frame's encoded telemetry and its fields (telemetry changes slower than frames)."""
        self._messages = select.poll()
        self._messages.register(conn.fileno(), select.POLLIN)
        """The pipe alone, asked with no wait before every frame (``Connection.poll`` builds a selector each time)."""
        self._idle = select.poll()
        for fd in (conn.fileno(), mailbox.fileno()):
            self._idle.register(fd, select.POLLIN)

    def serve(self) -> None:
        """Calls and notices first, then the frame on offer; sleep when there is neither. Returns at EOF.

        One message a frame, its result; the claim itself is in the mailbox (the platform's watchdog reads it there).
        """
        while True:
            try:
                while self._messages.poll(0):  # a message, or the end of the pipe (recv raises EOFError)
                    self.handle(TO_CHILD.decode(self.conn.recv_bytes()))
                offer = self.mailbox.claim()
                if offer is None:
                    self.mailbox.clear_wake()  # an offer made after this wakes the wait below
                    offer = self.mailbox.claim()
                if offer is None:
                    self._idle.poll()  # a call, a notice, EOF or an offer
                    continue
                while self.camera_gen < offer.camera_gen:  # its camera model was sent ahead of it: read on to it
                    self.handle(TO_CHILD.decode(self.conn.recv_bytes()))
            except (EOFError, OSError):
                return
            self.send(self.process(offer))

    def send(self, message: Result | Reply) -> None:
        """Send a result or reply; one with a value the wire does not take goes without its outputs, saying why."""
        try:
            send_message(self.conn, message)
        except (TypeError, ValueError, OverflowError) as exc:
            reason = f"the processor's outputs are not data: {exc}"
            if isinstance(message, Result):
                error = message.outcome.error
                send_message(self.conn, msgspec.structs.replace(message, saves=(), outcome=msgspec.structs.replace(
                    message.outcome, vector=None, outputs=NO_OUTPUTS, box=None, detections=None,
                    error=f"{error}\n{reason}" if error else reason)))
            else:
                send_message(self.conn, msgspec.structs.replace(message, ok=False, value=reason, saves=()))

    def handle(self, message: ToChild) -> None:
        if isinstance(message, Call):
            self.send(self.call(message))
        elif isinstance(message, Forget):
            self.slots.forget(message.slots)
        elif isinstance(message, Camera):
            self.telemetry.camera_model, self.camera_gen = camera_model(message), message.gen

    def process(self, offer: Offer) -> Result:
        if offer.telemetry != self._telemetry[0]:
            self._telemetry = (offer.telemetry, msgspec.msgpack.decode(offer.telemetry) if offer.telemetry else {})
        self.telemetry.begin(offer.seq, offer.t_mono_ns, offer.t_wall_ns, self._telemetry[1], offer.heartbeat_age_s)
        image = self.slots.view(offer.slot, offer.shape)
        outcome = call_frame(self.instance, image, vector=self.has_vector, outputs=self.outputs,
                             let_through=(MemoryError,), frame_seq=offer.seq, tracks=self.tracks,
                             seen_ns=offer.t_mono_ns, as_data=_plain)
        del image
        return Result(offer.gen, tuple(self.slots.released()), self._take_throttled(), outcome, self._take_saves())

    def _keep_save(self, image: np.ndarray, extra: dict[str, Any]) -> None:
        # A copy: the image as it is now, not with what photo_processing draws on it afterwards.
        kept = np.array(image) if self.save_images else None
        self.saves.append(Save(kept, {str(key): as_data(value) for key, value in extra.items()}))

    def _take_saves(self) -> tuple[Save, ...]:
        saves, self.saves = self.saves, []
        return tuple(saves)

    def _take_throttled(self) -> int:
        """``tmMgr.save`` calls throttled since the last result."""
        total = self.telemetry.saves_throttled
        count, self._throttled_sent = total - self._throttled_sent, total
        return count

    def call(self, call: Call) -> Reply:
        taken = time.monotonic_ns()
        try:
            value, ok = as_data(getattr(self.instance, call.method)(*call.args), arrays=False), True
        except MemoryError:
            raise
        except Exception as exc:  # noqa: BLE001 - handed to the operator as the command's error
            value, ok = f"{type(exc).__name__}: {exc}", False
        return Reply(call.call_id, ok, taken, tuple(self.slots.released()), value, self._take_saves())


def _plain(vector: Any) -> Any:
    """A vector as the wire takes it (its ``repr`` when it is not data, an array's too)."""
    return as_data(vector, arrays=False)


def main(fd: int, mailbox_address: str) -> int:
    faulthandler.enable()  # a segfault in native code leaves a Python traceback on stderr
    logging.basicConfig(level=os.environ.get(LOG_LEVEL_ENV, "WARNING"), handlers=[TaggedLogHandler()])
    _die_with_parent()
    _start_resource_tracker()
    conn = Connection(fd)
    mailbox = FrameMailbox.attach(mailbox_address)
    load = TO_CHILD.decode(conn.recv_bytes())
    assert isinstance(load, Load), load
    try:
        if too_small := _limit_memory(load.memory_mb):
            send_message(conn, LoadError(too_small, None, load.spec.rpartition(":")[2], None))
            return 0
        try:
            loaded = load_processor(load.spec, load.kwargs)
        except ProcessorLoadError as exc:
            send_message(conn, LoadError(str(exc), exc.path, exc.class_name, exc.missing))
            return 0
        send_message(conn, Ready(loaded.info))
        ChildRunner(conn, mailbox, loaded, save_images=load.save_images, save_max_hz=load.save_max_hz,
                    first_track_id=load.first_track_id).serve()
    except MemoryError:
        traceback.print_exc()
        print(f"processor_memory_mb = {load.memory_mb:g} MB reached", file=sys.stderr, flush=True)
        os._exit(MEMORY_EXIT_CODE)
    return 0


if __name__ == "__main__":
    sys.exit(main(int(sys.argv[1]), sys.argv[2]))
