"""The checked outputs a processor may give after each frame besides its vector: ``getLandingTarget`` and
``getGimbalPointing``. :func:`read_outputs` calls them and checks what they returned, so every host (the thread,
the processor's process) calls them the same way."""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass
from typing import TypeVar

from processors.base import GivesGimbalPointing, GivesLandingTarget, HasStatus
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


OUTPUT_METHODS = ("getLandingTarget", "getGimbalPointing")
"""The output methods, in the order they are called after a frame."""

NO_OUTPUTS = FrameOutputs()

STATUS_CHARS = 160
"""The longest ``landing_status`` kept (it is shown in an 80-column status line)."""


def output_methods(capabilities: Collection[str]) -> tuple[str, ...]:
    """The output methods among a processor's ``capabilities`` (detected at load time), in call order."""
    return tuple(name for name in OUTPUT_METHODS if name in capabilities)


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
    target = gimbal = None
    landing = "getLandingTarget" in methods
    if landing and isinstance(instance, GivesLandingTarget):
        target = read_landing_target(instance.getLandingTarget())
    if "getGimbalPointing" in methods and isinstance(instance, GivesGimbalPointing):
        gimbal = read_gimbal_pointing(instance.getGimbalPointing())
    if target is not None and frame_seq is not None:
        target.stamp(frame_seq)
    status = _one_line(instance.status if landing and target is None and isinstance(instance, HasStatus) else None)
    return FrameOutputs(target, gimbal, status)


def _one_line(status: object) -> str:
    """``status`` if it is text: its printable characters on one line, at most :data:`STATUS_CHARS`; else ""."""
    if not isinstance(status, str):
        return ""
    text = " ".join("".join(c if c.isprintable() else " " for c in status[:4 * STATUS_CHARS]).split())
    return text if len(text) <= STATUS_CHARS else text[:STATUS_CHARS - 3] + "..."
