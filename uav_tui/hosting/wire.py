"""Every message between the platform and the processor's process: typed records of plain data, the schema both
ends share.

Platform -> child: :class:`Load` first, then :class:`Call`, :class:`Forget` and :class:`Camera` in any order.
Child -> platform: :class:`Ready` or :class:`LoadError` once, then a :class:`Result` per frame claimed and a
:class:`Reply` per call. :mod:`uav_tui.hosting.codec` turns them into MessagePack and back.

Data only, because the child is not trusted: a processor can return any object, and what arrives is checked
against this schema when it is decoded (each value type's own ``__post_init__`` runs again in the platform), so a
value that is not data is that frame's error and nothing a processor does runs code in the platform (pickle
would call whatever ``__reduce__`` a returned object names). Each record is a MessagePack array, its kind's
number (``tag``) first, fields in the order written here.

Frames are not messages: the child claims the newest one in its
:class:`~uav_tui.hosting.frame_mailbox.FrameMailbox` and answers with a :class:`Result` for that offer's ``gen``.
"""

from __future__ import annotations

from typing import Any

import msgspec
import numpy as np

from processors.base import ProcessorInfo
from processors.outputs import NO_OUTPUTS, FrameOutputs
from uav_values.box import PixelBox
from uav_values.detections import Detected

Value = tuple[Any, ...] | dict[Any, Any] | str | bool | int | float | None
"""A value a processor returned (a vector, a call's answer), as plain data: a sequence arrives as a tuple (inside it,
lists), as from the thread host. The child sends an array or bytes as its ``repr``
(:func:`~uav_tui.hosting.codec.as_data`); one that arrives anyway (a hostile child) is a value of the wrong type to
the gate and text to the operator, never code."""


class _Record(msgspec.Struct, frozen=True, array_like=True):
    """A message: an array on the wire, its kind's number first."""


MAX_SAVE_PIXELS = 8192 * 8192
"""The largest ``tmMgr.save`` image a child may send (an 8K frame is a quarter of it)."""


class Save(_Record, frozen=True):
    """One ``tmMgr.save(frame, **extra)`` call: the image copied at the call (None when the platform does not
    record: nothing is copied or sent), and ``extra`` (plain data; arrays allowed).

    Checked on arrival: an image is 8-bit, grey or 3/4 channels, at most :data:`MAX_SAVE_PIXELS`; each field name
    is an identifier the recorder can make a column of (never ``frame``).
    """

    image: np.ndarray | None
    extra: dict[str, Any]

    def __post_init__(self) -> None:
        image = self.image
        if image is not None and not (image.dtype == np.uint8 and (image.ndim == 2 or image.ndim == 3
                                                                    and image.shape[2] in (1, 3, 4))
                                      and image.shape[0] * image.shape[1] <= MAX_SAVE_PIXELS):
            raise ValueError(f"a saved image must be 8-bit HxW or HxWx1/3/4 of at most {MAX_SAVE_PIXELS} pixels, "
                             f"not {image.dtype} {image.shape}")
        for name in self.extra:
            if not (isinstance(name, str) and name.isidentifier() and name != "frame"):
                raise ValueError(f"a saved field's name must be an identifier other than 'frame', not {name!r}")


class Load(_Record, frozen=True, tag=0):
    """The first message: cap the child's memory, then construct the processor."""

    spec: str
    kwargs: dict[str, Any]
    memory_mb: float | None
    save_images: bool
    save_max_hz: float
    first_track_id: int = 0
    """Where the platform's track numbers go on (:mod:`uav_tui.hosting.tracks`): a restarted processor's new
    tracks do not take the numbers of the ones recorded before."""


Argument = tuple[int | float, ...] | str | bool | int | float | None
"""An operator call's argument: an ROI ``(x, y, w, h)`` arrives as a tuple, as in a thread."""


class Call(_Record, frozen=True, tag=1):
    """An operator's call (``catch_cmd``, ``customize_processing``), answered with a :class:`Reply`."""

    call_id: int
    method: str
    args: tuple[Argument, ...]


class Forget(_Record, frozen=True, tag=2):
    """The platform freed these shared-memory slots: unmap them."""

    slots: tuple[str, ...]


class Camera(_Record, frozen=True, tag=3):
    """The source's camera model (``tmMgr.camera()``), sent at each change of source and to each new child: a
    :class:`~uav_values.camera.CameraModel`, encoded (:func:`uav_tui.hosting.codec.camera_message`) and decoded
    when it arrives (:func:`~uav_tui.hosting.codec.camera_model`).

    ``gen`` numbers the models from 1; each frame's offer names the one it is of
    (:attr:`~uav_tui.hosting.frame_mailbox.Offer.camera_gen`). The pipe and the mailbox are two channels, so a child
    may claim a frame before it has read the message sent ahead of it: it reads the pipe until it has."""

    gen: int
    model: msgspec.Raw


class Ready(_Record, frozen=True, tag=4):
    """The processor is constructed."""

    info: ProcessorInfo


class LoadError(_Record, frozen=True, tag=5):
    """The processor could not be loaded (the fields of a :class:`~processors.errors.ProcessorLoadError`)."""

    message: str
    path: str | None
    class_name: str | None
    missing: str | None


class FrameOutcome(msgspec.Struct, frozen=True, array_like=True):
    """What one call into the processor did with one frame (:func:`~uav_tui.hosting.frame_call.call_frame`): the
    frame's one record, from that call to the relays, handed on untouched (monotonic ns times).

    The thread host hands the record the call made; the processor's process sends it inside its :class:`Result`
    and the platform decodes the same type, checked.
    """

    t_start_ns: int
    t_end_ns: int
    """When ``photo_processing`` returned, or when it (or what followed) raised."""
    t_vector_ns: int = 0
    """When ``getPreparedVector`` returned (0 when not called)."""
    vector: Value = None
    """What ``getPreparedVector`` returned, unchecked (the autonomy gate checks it); from the processor's process,
    as plain data (:data:`Value`)."""
    outputs: FrameOutputs = NO_OUTPUTS
    """What the output methods returned, checked (:mod:`processors.outputs`): ``outputs.landing_target``
    (getLandingTarget), ``outputs.gimbal`` (getGimbalPointing), ``outputs.get(field)`` for any; None each without
    the method, or nothing this frame."""
    box: PixelBox | None = None
    """The processor's ``box`` attribute after this frame (what it tracks), or None."""
    detections: tuple[Detected, ...] | None = None
    """The processor's ``detections``, checked and numbered (None without the attribute, or on an error)."""
    error: str | None = None
    """The traceback's text when the processor raised."""
    raised: str = ""
    """The exception in one line (:func:`~uav_tui.hosting.frame_call.describe`) when the processor raised."""


class Times(msgspec.Struct, frozen=True, array_like=True):
    """The leading fields of a :class:`FrameOutcome`: read alone when the whole does not decode."""

    t_start_ns: int
    t_end_ns: int
    t_vector_ns: int


class Result(_Record, frozen=True, tag=6):
    """One claimed frame's outcome, with what the platform needs beside it.

    The fields up to ``outcome``'s times are :class:`ResultHead`'s: what the platform still reads when the rest
    does not decode, to free the frame's slots and count its error.
    """

    gen: int
    released: tuple[str, ...]
    """Slots the child no longer references: a processor may keep a frame (the previous one, for optical flow) and
    the platform must not reuse its slot until it lets go."""
    saves_throttled: int
    """``tmMgr.save`` calls dropped above ``save_max_hz`` since the last result (in the child, before any copy)."""
    outcome: FrameOutcome
    saves: tuple[Save, ...]
    """The ``tmMgr.save`` calls made since the last message."""


class ResultHead(_Record, frozen=True, tag=6):
    """The leading fields of a :class:`Result`: read alone when the whole does not decode."""

    gen: int
    released: tuple[str, ...]
    saves_throttled: int
    outcome: Times


class Reply(_Record, frozen=True, tag=7):
    """A :class:`Call`'s answer: its value, or (``ok`` False) ``Type: message`` of what it raised."""

    call_id: int
    ok: bool
    t_taken_ns: int
    """When the processor began the call (monotonic ns)."""
    released: tuple[str, ...]
    value: Value
    saves: tuple[Save, ...]


class ReplyHead(_Record, frozen=True, tag=7):
    """The leading fields of a :class:`Reply`: read alone when the whole does not decode."""

    call_id: int
    ok: bool
    t_taken_ns: int
    released: tuple[str, ...]


ToChild = Load | Call | Forget | Camera
FromChild = Ready | LoadError | Result | Reply
Message = ToChild | FromChild
