"""The checked outputs a processor may give after each frame besides its vector: ``getLandingTarget`` and
``getGimbalPointing``. One table (:data:`READERS`) says which method gives which output, how it is called and how
it is checked, so every host (the thread, the processor's process) calls them the same way; an output entered there
without a field of its own in :class:`FrameOutputs` is kept in :attr:`FrameOutputs.more`."""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import dataclass, field, fields
from typing import Any, TypeVar

from uav_values.gimbal import GimbalPointing
from uav_values.landing_target import LandingTarget

T = TypeVar("T")


@dataclass(frozen=True, slots=True)
class FrameOutputs:
    """What the output methods returned after one frame, checked (None: no method, or nothing this frame)."""

    landing_target: LandingTarget | None = None
    gimbal: GimbalPointing | None = None
    landing_status: str = ""
    """A processor with ``getLandingTarget`` that gave no target: its ``status`` attribute, the reason it gives
    (``2 markers with id 7: which is the pad? no target``), one line of at most :data:`STATUS_CHARS` characters."""
    more: dict[str, Any] = field(default_factory=dict)
    """The outputs of :data:`READERS` without a field above, by their field name (from the processor's process, as
    plain data: a field of their own carries their type across)."""

    def get(self, name: str) -> Any:
        """The output named ``name`` in :data:`READERS` (its own field first, else its entry in :attr:`more`), None
        without it."""
        return getattr(self, name) if name in _FIELDS else self.more.get(name)


def read_output(value: object, kind: type[T], method: str, hint: str) -> T | None:
    """What an output method (``method``) returned, checked: a ``kind`` or None.

    Raises:
        TypeError: anything else, saying what was returned and ``hint`` (what to return instead); it is reported
            as the processor's error and nothing is sent.
    """
    if value is None or isinstance(value, kind):
        return value
    raise TypeError(f"{method} returned {type(value).__name__} {value!r:.80}: return {hint}")


def read_landing_target(value: object) -> LandingTarget | None:
    """What ``getLandingTarget()`` returned, checked: a :class:`LandingTarget` or None."""
    return read_output(value, LandingTarget, "getLandingTarget()", "a processors.LandingTarget or None")


def read_gimbal_pointing(value: object) -> GimbalPointing | None:
    """What ``getGimbalPointing()`` returned, checked: a :class:`GimbalPointing` or None."""
    return read_output(value, GimbalPointing, "getGimbalPointing()",
                       "processors.GimbalPointing.rates(pitch, yaw) or .angles(pitch, yaw), or None")


@dataclass(frozen=True, slots=True)
class Reader:
    """One output method: the :class:`FrameOutputs` field (or :attr:`~FrameOutputs.more` key) it fills, the call of
    the method on a processor that has it (through its Protocol: None from one that has not), and the check of what
    it returned (raises TypeError on a wrong type)."""

    output: str
    call: Callable[[object], object]
    check: Callable[[object], Any]


def _landing_target(instance: object) -> object:
    method = getattr(instance, "getLandingTarget", None)  # optional: see processors.base.FrameProcessor
    return method() if method is not None else None


def _gimbal_pointing(instance: object) -> object:
    method = getattr(instance, "getGimbalPointing", None)  # optional: see processors.base.FrameProcessor
    return method() if method is not None else None


READERS: dict[str, Reader] = {
    "getLandingTarget": Reader("landing_target", _landing_target, read_landing_target),
    "getGimbalPointing": Reader("gimbal", _gimbal_pointing, read_gimbal_pointing),
}
"""Output method -> its :class:`Reader`, in the order they are called after a frame."""

NO_OUTPUTS = FrameOutputs()

_FIELDS = frozenset(f.name for f in fields(FrameOutputs)) - {"more"}

STATUS_CHARS = 160
"""The longest ``landing_status`` kept (it is shown in an 80-column status line)."""


def output_methods(capabilities: Collection[str]) -> tuple[str, ...]:
    """The output methods among a processor's ``capabilities`` (detected at load time), in :data:`READERS` order."""
    return tuple(name for name in READERS if name in capabilities)


def read_outputs(instance: object, methods: Collection[str], frame_seq: int | None = None) -> FrameOutputs:
    """Call each of ``methods`` (output methods) on ``instance`` and check what it returned.

    A landing target without a ``frame_seq`` is stamped with ``frame_seq`` (the frame just processed,
    :meth:`~uav_values.landing_target.LandingTarget.stamp`): the same object returned after a later frame then
    says it was seen in this one, and is not sent for that one.

    Raises:
        TypeError: a method returned a value of the wrong type; whatever a method raised propagates.
    """
    if not methods:
        return NO_OUTPUTS
    values: dict[str, Any] = {}
    more: dict[str, Any] = {}
    for name in methods:
        reader = READERS[name]
        (values if reader.output in _FIELDS else more)[reader.output] = reader.check(reader.call(instance))
    target = values.get("landing_target")
    if target is not None and frame_seq is not None:
        target.stamp(frame_seq)
    if "getLandingTarget" in methods and target is None:
        values["landing_status"] = _one_line(getattr(instance, "status", None))
    return FrameOutputs(**values, more=more)


def _one_line(status: object) -> str:
    """``status`` if it is text: its printable characters on one line, at most :data:`STATUS_CHARS`; else ""."""
    if not isinstance(status, str):
        return ""
    text = " ".join("".join(c if c.isprintable() else " " for c in status[:4 * STATUS_CHARS]).split())
    return text if len(text) <= STATUS_CHARS else text[:STATUS_CHARS - 3] + "..."
