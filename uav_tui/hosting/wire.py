"""Every message between the platform and the processor's process: typed values, the same at both ends.

Platform -> child, pickled by :meth:`multiprocessing.connection.Connection.send`: :class:`Load` first, then
:class:`Call`, :class:`Forget` and :class:`Camera` in any order. Child -> platform, through
:func:`uav_tui.hosting.pipe.send_message` (pickle protocol 5, arrays out of band): :class:`Ready` or
:class:`LoadError` once, then a :class:`Result` per frame claimed and a :class:`Reply` per call.

Frames are not messages: the child claims the newest one in its
:class:`~uav_tui.hosting.frame_mailbox.FrameMailbox` and answers with a :class:`Result` for that offer's ``gen``.

On the pipe a message is a plain tuple, its kind's number first (:func:`pack`, :func:`unpack`, at both ends):
pickle takes a NamedTuple apart through Python-level calls, and a result crosses every frame. A ``Result``
pickled as the NamedTuple took 10.5 us to dump and 4.5 us to load, packed 3.6 and 2.6 us (the untyped tuple it
replaces: 1.0 and 2.0 us; least of 7 runs of 20,000 on a loaded x86 machine).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from processors.base import Box, ProcessorInfo
from processors.detections import Detected
from processors.outputs import FrameOutputs

if TYPE_CHECKING:
    from sources.camera_model import CameraModel

Save = tuple[np.ndarray | None, dict[str, Any]]
"""One ``tmMgr.save(frame, **extra)`` call: the image copied at the call (None when the platform does not record:
nothing is copied or sent), and ``extra``."""


class Load(NamedTuple):
    """The first message: cap the child's memory, then construct the processor."""

    spec: str
    kwargs: dict[str, Any]
    memory_mb: float | None
    save_images: bool
    save_max_hz: float


class Call(NamedTuple):
    """An operator's call (``catch_cmd``, ``customize_processing``), answered with a :class:`Reply`."""

    call_id: int
    method: str
    args: tuple[Any, ...]


class Forget(NamedTuple):
    """The platform freed these shared-memory slots: unmap them."""

    slots: list[str]


class Camera(NamedTuple):
    """The source's camera model (``tmMgr.camera()``), sent at each change of source."""

    model: CameraModel | None


class Ready(NamedTuple):
    """The processor is constructed."""

    info: ProcessorInfo


class LoadError(NamedTuple):
    """The processor could not be loaded (the fields of a :class:`~processors.errors.ProcessorLoadError`)."""

    message: str
    path: str | None
    class_name: str | None
    missing: str | None


class Result(NamedTuple):
    """One claimed frame's outcome (monotonic ns times; ``t_vector_ns`` 0 without ``getPreparedVector``)."""

    gen: int
    t_start_ns: int
    t_end_ns: int
    t_vector_ns: int
    vector: Any
    outputs: FrameOutputs | None
    """What the output methods returned, checked (:mod:`processors.outputs`); None when none gave anything, the
    usual frame: a dataclass costs about 6 us a frame to pickle and load, None nothing."""
    box: Box | None
    detections: tuple[Detected, ...] | None
    """The processor's ``detections``, checked (None without the attribute)."""
    error: str | None
    """Traceback text if the processor raised."""
    saves: list[Save]
    """The ``tmMgr.save`` calls made since the last message."""
    saves_throttled: int
    """``tmMgr.save`` calls dropped above ``save_max_hz`` since the last result (in the child, before any copy)."""
    released: list[str]
    """Slots the child no longer references: a processor may keep a frame (the previous one, for optical flow) and
    the platform must not reuse its slot until it lets go."""


class Reply(NamedTuple):
    """A :class:`Call`'s answer: its value, or (``ok`` False) ``Type: message`` of what it raised."""

    call_id: int
    ok: bool
    value: Any
    t_taken_ns: int
    """When the processor began the call (monotonic ns)."""
    saves: list[Save]
    released: list[str]


ToChild = Load | Call | Forget | Camera
FromChild = Ready | LoadError | Result | Reply
Message = ToChild | FromChild

_KINDS: tuple[type[Message], ...] = (Load, Call, Forget, Camera, Ready, LoadError, Result, Reply)
_NUMBERS = {kind: number for number, kind in enumerate(_KINDS)}


def pack(message: Message) -> tuple[Any, ...]:
    """``message`` as it travels: its kind's number, then its fields."""
    return (_NUMBERS[type(message)], *message)


def unpack(packed: tuple[Any, ...]) -> Message:
    """The message :func:`pack` made ``packed`` from."""
    return _KINDS[packed[0]]._make(packed[1:])
