"""Frame processors: the researcher's algorithms.

``load_processor("csrt")``, ``load_processor("processors.template:MeanBrightnessProcessor")`` or
``load_processor("~/algos/mine.py:MyAnalyzer")`` returns a validated :class:`LoadedProcessor`.
Installed packages add names through the ``uav_tui.processors`` entry-point group.
"""

from __future__ import annotations

from typing import Any

from processors.base import OPTIONAL_METHODS, FrameProcessor, ProcessorInfo, validate_processor
from processors.loading import ENTRY_POINT_GROUP, LoadedProcessor, load
from uav_values.gimbal import GimbalPointing
from uav_values.landing_target import LandingTarget

BUILTINS: dict[str, str] = {
    "template": "processors.template:MeanBrightnessProcessor",
    "nanotrack": "processors.nanotrack_tracker:NanoTrackProcessor",
    "csrt": "processors.csrt_tracker:CSRTTrackingProcessor",
    "position_hold": "processors.position_hold:SIFTPositionHold",
    "yolo": "processors.yolo_detector:YoloDetector",
    "precision_land": "processors.precision_land:PrecisionLand",
}
"""Short names of the built-in processors."""

# LandingTarget and GimbalPointing live in uav_values; the manual gives them as ``from processors import ...``.

__all__ = [
    "BUILTINS", "ENTRY_POINT_GROUP", "OPTIONAL_METHODS", "FrameProcessor", "GimbalPointing", "LandingTarget",
    "LoadedProcessor",
    "ProcessorInfo",
    "load_processor", "validate_processor",
]


def load_processor(spec: str, kwargs: dict[str, Any] | None = None, *, fresh: bool = False) -> LoadedProcessor:
    """Import, construct (with ``kwargs``) and validate the processor ``spec`` names."""
    return load(spec, BUILTINS, kwargs, fresh=fresh)
