"""The frame-processor contract: one required method, five optional ones, names as published."""

from __future__ import annotations

import difflib
import inspect
import math
import re
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from processors.errors import ProcessorLoadError
from uav_values.box import PixelBox

if TYPE_CHECKING:
    from processors.frame_telemetry import FrameTelemetry

OPTIONAL_METHODS = ("catch_cmd", "customize_processing", "getPreparedVector", "getLandingTarget",
                    "getGimbalPointing")
"""Detected once at load time; a processor without ``getPreparedVector`` never moves the vehicle, one without
``getLandingTarget`` never sends a landing target, one without ``getGimbalPointing`` never turns the gimbal."""

_SIGNATURES = ("catch_cmd(self, roi)", "customize_processing(self, id)", "getPreparedVector(self)",
               "getLandingTarget(self)", "getGimbalPointing(self)")

@runtime_checkable
class FrameProcessor(Protocol):
    """What a researcher writes. No base class is needed; this Protocol is for type checkers.

    ``photo_processing(frame)`` gets the newest BGR uint8 frame and may draw its overlay on it
    in place (previews show that array). The optional methods::

        catch_cmd(roi)            operator selected (x, y, w, h) in frame pixels
        customize_processing(id)  operator pressed F1..F4 (id 1..4)
        getPreparedVector()       (vx, vy, t): body-frame m/s, vx forward, vy right, t seconds; or None
        getLandingTarget()        the landing pad seen in the frame just processed, a
                                  :class:`~uav_values.landing_target.LandingTarget`; or None
        getGimbalPointing()       where the camera should turn after the frame just processed, a
                                  :class:`~uav_values.gimbal.GimbalPointing` (rates or angles); or None

    ``tmMgr`` is set by the platform after construction (a :class:`~processors.frame_telemetry.FrameTelemetry`:
    ``snapshot()``, the telemetry at the frame's capture with its ``frame_seq`` and ``frame_t_ns``, the clock
    to pace by; ``save(frame, **extra)``). All calls come from one thread.

    Two optional read-only attributes, read by the platform after every frame: ``box``, ``(x, y, w, h)`` in
    frame pixels of what the processor tracks now, or ``None`` (nothing selected, or lost); ``detections``,
    several boxes with a label and a score (:mod:`processors.detections`).

    The platform reads the optional members with ``getattr(instance, name, None)``: ``isinstance`` against a
    runtime-checkable Protocol asks the same (``hasattr`` of each member) at 5-10 µs a call on Python 3.11,
    paid on every frame and every detection.
    """

    tmMgr: FrameTelemetry | None

    def photo_processing(self, frame: np.ndarray) -> Any: ...


@dataclass(frozen=True)
class ProcessorInfo:
    """What the platform learned about a processor class when it loaded it."""

    name: str
    """``module:Class`` or ``file.py:Class`` as loaded."""
    path: str | None
    """The source file, for reloads and error messages."""
    capabilities: frozenset[str]
    """Which of OPTIONAL_METHODS it implements."""
    warnings: tuple[str, ...] = ()
    """What looks wrong but loads: a method named like a contract method but not quite (never called)."""
    buttons: tuple[tuple[int, str], ...] = ()
    """``(id, meaning)`` of the F-keys its class docstring describes under ``Operator buttons:``."""


def validate_processor(instance: object, *, name: str, path: str | None) -> ProcessorInfo:
    """Check ``instance`` against the contract; raises ProcessorLoadError naming what is missing."""
    class_name = type(instance).__name__
    method = getattr(instance, "photo_processing", None)
    where = f"{class_name} in {path}" if path else class_name
    if not callable(method):
        raise ProcessorLoadError(
            f"{where} has no photo_processing(self, frame) method: it is the one method a processor must have",
            path=path, class_name=class_name, missing="photo_processing",
        )
    _require_arity(method, 1, where, path, class_name, "photo_processing(self, frame)")
    capabilities = set()
    for optional, signature in zip(OPTIONAL_METHODS, _SIGNATURES, strict=True):
        candidate = getattr(instance, optional, None)
        if candidate is None:
            continue
        if not callable(candidate):
            raise ProcessorLoadError(f"{where}.{optional} is not a method; expected {signature}",
                                     path=path, class_name=class_name, missing=optional)
        _require_arity(candidate, signature.count(",") , where, path, class_name, signature)
        capabilities.add(optional)
    if not hasattr(instance, "tmMgr"):
        instance.tmMgr = None  # type: ignore[attr-defined]
    return ProcessorInfo(name=name, path=path, capabilities=frozenset(capabilities),
                         warnings=misspelt_methods(type(instance)), buttons=described_buttons(type(instance)))


CONTRACT_NAMES = ("photo_processing", *OPTIONAL_METHODS, "tmMgr")
"""Every name the platform calls or sets on a processor."""

_BUTTON = re.compile(r"^\s*F([1-4])\s*:\s*(.+?)\s*$")


def misspelt_methods(cls: type) -> tuple[str, ...]:
    """A warning for each public name of ``cls`` close to a contract name it does not define (``getPreparedVectr``,
    ``customise_processing``): as written, the platform never calls it."""
    defined = {name for name in dir(cls) if not name.startswith("_")}
    lowered = {name.lower(): name for name in CONTRACT_NAMES}
    warnings = []
    for name in sorted(defined - set(CONTRACT_NAMES)):
        close = ([lowered[name.lower()]] if name.lower() in lowered else
                 difflib.get_close_matches(name, CONTRACT_NAMES, n=1, cutoff=0.8))
        if close and close[0] not in defined:
            warnings.append(f"{cls.__name__}.{name} is not a name the platform calls: did you mean {close[0]}? "
                            "(as written it is never called)")
    return tuple(warnings)


def described_buttons(cls: type) -> tuple[tuple[int, str], ...]:
    """The ``F1: ...`` lines under ``Operator buttons:`` in the docstring of ``cls`` or of a class it inherits."""
    docs = (inspect.cleandoc(klass.__doc__ or "") for klass in cls.__mro__)
    section = next((doc.partition("Operator buttons:")[2] for doc in docs if "Operator buttons:" in doc), "")
    buttons: list[tuple[int, str]] = []
    for line in section.splitlines()[1:]:
        match = _BUTTON.match(line)
        if match is None:
            if buttons:
                break
            continue
        buttons.append((int(match.group(1)), match.group(2).rstrip(".")))
    return tuple(buttons)


def _require_arity(method: Any, count: int, where: str, path: str | None, class_name: str, signature: str) -> None:
    try:
        inspect.signature(method).bind(*([None] * count))
    except TypeError:
        raise ProcessorLoadError(f"{where}: wrong signature for {method.__name__}; expected {signature}",
                                 path=path, class_name=class_name, missing=signature) from None
    except ValueError:  # builtins without a signature: accept
        pass


def read_box(instance: object) -> PixelBox | None:
    """The processor's ``box`` attribute as whole frame pixels, or None when absent, None or malformed.

    A box is 4 finite numbers with positive width and height; anything else reads as None, so a
    researcher's half-finished attribute can never break the frame it belongs to.
    """
    value: Any = getattr(instance, "box", None)  # optional: see FrameProcessor
    if value is None:
        return None
    try:
        x, y, w, h = (float(v) for v in value)
    except (TypeError, ValueError, OverflowError):
        return None
    if not all(math.isfinite(v) and abs(v) < 1e7 for v in (x, y, w, h)) or w <= 0 or h <= 0:
        return None
    return round(x), round(y), max(1, round(w)), max(1, round(h))
