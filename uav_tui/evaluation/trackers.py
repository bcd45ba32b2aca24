"""What ``uav-tui eval`` scores: a processor loaded as ``--processor`` loads it, or a plain OpenCV tracker."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from processors import load_processor
from processors.errors import ProcessorLoadError

OPENCV_PREFIX = "cv:"
OPENCV_PROCESSOR = "processors.opencv_tracker:OpenCVTracker"
"""``cv:NAME`` is this processor with ``tracker=NAME``: baselines take the same code path as any processor."""


@dataclass(frozen=True)
class TrackerSpec:
    """A processor spec (short name, ``module:Class``, ``file.py:Class`` or ``cv:NAME``) and its arguments."""

    spec: str
    kwargs: dict[str, Any] = field(default_factory=dict)

    @property
    def label(self) -> str:
        """``csrt mode=paper``: the name in tables, plots and JSON."""
        return " ".join([self.spec, *(f"{key}={value}" for key, value in self.kwargs.items())])

    def load(self) -> Any:
        """Construct the processor; it must have ``catch_cmd`` (the first box is given through it).

        Raises:
            ProcessorLoadError: as for ``--processor``, or it has no ``catch_cmd``.
        """
        spec, kwargs = self.spec, dict(self.kwargs)
        if spec.startswith(OPENCV_PREFIX):
            spec, kwargs = OPENCV_PROCESSOR, {"tracker": spec[len(OPENCV_PREFIX):].lower(), **kwargs}
        loaded = load_processor(spec, kwargs)
        if "catch_cmd" not in loaded.info.capabilities:
            raise ProcessorLoadError(f"{loaded.info.name} has no catch_cmd(self, roi): eval starts a tracker with "
                                     "the first gt box through it", path=loaded.info.path,
                                     class_name=type(loaded.instance).__name__, missing="catch_cmd")
        return loaded.instance
