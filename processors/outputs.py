"""The checked outputs a processor may give after each frame besides its vector: ``getLandingTarget`` and
``getGimbalPointing``. One table says which method gives which output and how it is checked, so every host (the
thread, the processor's process) calls them the same way."""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import dataclass
from typing import Any

from processors.gimbal import GimbalPointing, read_gimbal_pointing
from processors.landing_target import LandingTarget, read_landing_target


@dataclass(frozen=True, slots=True)
class FrameOutputs:
    """What the output methods returned after one frame, checked (None: no method, or nothing this frame)."""

    landing_target: LandingTarget | None = None
    gimbal: GimbalPointing | None = None


READERS: dict[str, tuple[str, Callable[[object], Any]]] = {
    "getLandingTarget": ("landing_target", read_landing_target),
    "getGimbalPointing": ("gimbal", read_gimbal_pointing),
}
"""Output method -> (:class:`FrameOutputs` field, the check of what it returned: raises TypeError on a wrong type)."""

NO_OUTPUTS = FrameOutputs()


def output_methods(capabilities: Collection[str]) -> tuple[str, ...]:
    """The output methods among a processor's ``capabilities`` (detected at load time), in :data:`READERS` order."""
    return tuple(name for name in READERS if name in capabilities)


def read_outputs(instance: Any, methods: Collection[str]) -> FrameOutputs:
    """Call each of ``methods`` (output methods) on ``instance`` and check what it returned.

    Raises:
        TypeError: a method returned a value of the wrong type; whatever a method raised propagates.
    """
    if not methods:
        return NO_OUTPUTS
    values = {}
    for name in methods:
        field, read = READERS[name]
        values[field] = read(getattr(instance, name)())
    return FrameOutputs(**values)
