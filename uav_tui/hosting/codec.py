"""The :mod:`~uav_tui.hosting.wire` messages as bytes: MessagePack (``msgspec``), arrays beside it, checked on arrival.

A message is one MessagePack document; each NumPy array in it (a ``tmMgr.save`` image, a camera model's
matrices) is an extension value naming its dtype and shape, its bytes either out of band (:data:`OUT_OF_BAND`:
the index of a buffer sent after the document, written straight from the array's memory and read into a buffer
of its own, never copied again) or inline (:data:`INLINE`, for the platform's small arrays). Only numeric dtypes
are arrays; an extension value of any other kind, a dtype or shape that does not match its bytes, or a field that
does not fit the schema is a :class:`WireError`.

At the child's end NumPy scalars and subclasses of the built-in types become the built-in value; anything else
is refused there (:func:`as_data` puts its ``repr`` in its place, as the text it is).
"""

from __future__ import annotations

import math
from typing import Any

import msgspec
import numpy as np

from uav_tui.hosting.wire import Camera, FromChild, Message, ReplyHead, ResultHead, ToChild
from uav_values.camera import CameraModel

OUT_OF_BAND = 1
"""Extension code: an array whose bytes are buffer ``index`` after the document: ``[index, dtype, shape]``."""
INLINE = 2
"""Extension code: an array with its bytes in the document: ``[dtype, shape, bytes]``."""
BIG_INT = 3
"""Extension code: an integer beyond MessagePack's 64 bits, in decimal (Python's own limit on its digits holds)."""
ARRAY_KINDS = frozenset("biuf")
"""The dtype kinds an array may have (bool, signed, unsigned, float): never objects."""


class WireError(ValueError):
    """A message that is not what the schema says (the text says where); nothing in it was used."""


class Encoder:
    """Turns messages into a document and the arrays that go after it (``out_of_band``) or inside it."""

    def __init__(self, *, out_of_band: bool) -> None:
        self._out_of_band = out_of_band
        self._arrays: list[np.ndarray] = []
        self._encoder = msgspec.msgpack.Encoder(enc_hook=self._hook)

    def encode(self, message: Message | CameraModel | None) -> tuple[bytes, list[np.ndarray]]:
        """The document and its out-of-band arrays (C-contiguous, in order).

        Raises:
            TypeError: a value that is not data (the message names its type).
        """
        self._arrays = []
        try:
            return self._encoder.encode(message), self._arrays
        finally:
            self._arrays = []

    def _hook(self, value: Any) -> Any:
        if isinstance(value, _BigInt):
            return msgspec.msgpack.Ext(BIG_INT, str(int(value)).encode())
        if isinstance(value, np.ndarray) and value.dtype.kind in ARRAY_KINDS:
            array = np.ascontiguousarray(value)
            if self._out_of_band:
                self._arrays.append(array)
                return msgspec.msgpack.Ext(OUT_OF_BAND, _ENCODE((len(self._arrays) - 1, array.dtype.str,
                                                                  array.shape)))
            return msgspec.msgpack.Ext(INLINE, _ENCODE((array.dtype.str, array.shape, array.tobytes())))
        if isinstance(value, np.generic):
            return value.item()
        # A subclass of a built-in type: its plain value (the base type's own conversion, none of its methods).
        if isinstance(value, int):
            return int.__int__(value)
        if isinstance(value, float):
            return float.__float__(value)
        if isinstance(value, str):
            return str.__str__(value)
        if isinstance(value, bytes):
            return bytes(memoryview(value))
        raise TypeError(f"a {type(value).__name__} is not data: return numbers, text, lists, dicts or NumPy arrays")


_ENCODE = msgspec.msgpack.encode


class Decoder:
    """Turns what arrived back into a message, checked against the schema; arrays from the buffers given."""

    def __init__(self, kinds: Any) -> None:
        self._buffers: list[bytearray] = []
        self._decoder = msgspec.msgpack.Decoder(kinds, ext_hook=self._ext, dec_hook=_arrays_only)

    def decode(self, data: bytes | memoryview, buffers: list[bytearray] | None = None) -> Any:
        """The message in ``data``.

        Raises:
            WireError: it does not decode, or does not fit the schema (the text says where).
        """
        self._buffers = buffers or []
        try:
            return self._decoder.decode(data)
        except RecursionError:
            raise WireError("nested deeper than the interpreter's recursion limit") from None
        except Exception as exc:  # noqa: BLE001 - whatever the bytes make msgspec or a hook raise: not a message
            raise WireError(f"{type(exc).__name__}: {exc}"[:500]) from None
        finally:
            self._buffers = []

    def _ext(self, code: int, data: memoryview) -> np.ndarray | int:
        if code == OUT_OF_BAND:
            index, dtype, shape = _DECODE_HEAD(data)
            if not 0 <= index < len(self._buffers):
                raise ValueError(f"array buffer {index} was not sent ({len(self._buffers)} were)")
            return _array(dtype, shape, self._buffers[index])
        if code == INLINE:
            dtype, shape, raw = _DECODE_INLINE(data)
            return _array(dtype, shape, bytearray(raw))
        if code == BIG_INT:
            return int(bytes(data).decode("ascii"))
        raise ValueError(f"unknown extension type {code}")


_DECODE_HEAD = msgspec.msgpack.Decoder(tuple[int, str, tuple[int, ...]]).decode
_DECODE_INLINE = msgspec.msgpack.Decoder(tuple[str, tuple[int, ...], bytes]).decode


def _array(dtype_text: str, shape: tuple[int, ...], buffer: bytearray) -> np.ndarray:
    dtype = np.dtype(dtype_text)
    if dtype.kind not in ARRAY_KINDS or dtype.fields is not None or dtype.subdtype is not None:
        raise ValueError(f"array dtype {dtype_text!r} is not a number type")
    if any(n < 0 for n in shape) or math.prod(shape) * dtype.itemsize != len(buffer):
        raise ValueError(f"array shape {shape} of {dtype_text} does not match its {len(buffer)} bytes")
    return np.frombuffer(buffer, dtype).reshape(shape)


def _arrays_only(kind: type, value: Any) -> Any:
    """The decoder's hook for fields typed ``np.ndarray``: an array extension value, nothing else."""
    if kind is np.ndarray and isinstance(value, np.ndarray):
        return value
    raise NotImplementedError


FROM_CHILD = Decoder(FromChild)
"""The platform's decoder of what a child sends."""
TO_CHILD = Decoder(ToChild)
"""The child's decoder of what the platform sends."""
_HEADS = Decoder(ResultHead | ReplyHead)


def decode_from_child(data: bytes | memoryview, buffers: list[bytearray]) -> FromChild:
    """A child's message, checked.

    Raises:
        UnreadableResult: a result or reply whose head decodes but not the rest (the frame or call it answers
            is known, and what it released).
        WireError: anything else that does not decode.
    """
    try:
        message: FromChild = FROM_CHILD.decode(data, buffers)
    except WireError as exc:
        try:
            head = _HEADS.decode(data, buffers)
        except WireError:
            raise exc from None
        raise UnreadableResult(head, str(exc)) from None
    return message


class UnreadableResult(WireError):
    """A result or reply that does not fit the schema; ``head`` is what could be read of it."""

    def __init__(self, head: ResultHead | ReplyHead, reason: str) -> None:
        super().__init__(reason)
        self.head = head
        self.reason = reason


def camera_message(gen: int, model: CameraModel | None) -> Camera:
    """The :class:`~uav_tui.hosting.wire.Camera` message for ``model``, the ``gen``-th."""
    return Camera(gen, msgspec.Raw(Encoder(out_of_band=False).encode(model)[0]))


def camera_model(message: Camera) -> CameraModel | None:
    """The camera model a :class:`~uav_tui.hosting.wire.Camera` message carries.

    Raises:
        WireError: it is not a camera model.
    """
    if bytes(message.model) == _NONE:
        return None
    return Decoder(CameraModel).decode(message.model)


_NONE = msgspec.msgpack.encode(None)


def as_data(value: Any, *, arrays: bool = True) -> Any:
    """``value`` itself when the wire takes it (the child's encoder; an array or bytes only with ``arrays``), else
    its ``repr`` cut to 200 characters: what a researcher returned is reported, never fatal."""
    if not arrays and isinstance(value, np.ndarray | bytes):
        return _repr(value)
    for attempt in (value, None):
        try:
            _CHECK.encode(value)
        except OverflowError:
            if attempt is None:
                break
            try:
                value = _big_ints(value)
            except RecursionError:
                break
        except (TypeError, ValueError, RecursionError):
            break
        else:
            return value
    return _repr(value)


def _repr(value: Any) -> str:
    """``repr(value)`` cut to 200 characters; the type's name when even that fails (a value nested too deep)."""
    try:
        return repr(value)[:200]
    except Exception:  # noqa: BLE001 - a researcher's __repr__ may raise anything
        return f"<a {type(value).__name__} whose repr failed>"


def _checked(value: Any) -> Any:
    """The wire check of an array without its bytes (``tmMgr.save`` fields are checked, not copied twice)."""
    if isinstance(value, np.ndarray) and value.dtype.kind in ARRAY_KINDS:
        return None
    return _PLAIN_HOOK(value)


class _BigInt(int):
    """An integer MessagePack cannot hold: sent as :data:`BIG_INT`."""


def _big_ints(value: Any) -> Any:
    """``value`` with its integers beyond 64 bits marked for :data:`BIG_INT` (in tuples, lists and dict values)."""
    if isinstance(value, int) and not isinstance(value, bool) and not -2**63 <= value < 2**64:
        return _BigInt(value)
    if isinstance(value, tuple | list):
        return type(value)(_big_ints(v) for v in value) if type(value) in (tuple, list) else value  # not a subclass
    if isinstance(value, dict):
        return {k: _big_ints(v) for k, v in value.items()}
    return value


_PLAIN_HOOK = Encoder(out_of_band=False)._hook
PLAIN = msgspec.msgpack.Encoder(enc_hook=_PLAIN_HOOK)
"""Values as plain data (NumPy scalars as numbers, arrays inline): the telemetry a frame carries to the child."""
_CHECK = msgspec.msgpack.Encoder(enc_hook=_checked)

