"""Object-detection backends for :mod:`processors.yolo_detector`, chosen by the model file.

| model file | backend | needs |
|---|---|---|
| ``*.pt`` | Ultralytics (PyTorch) | the ``yolo`` extra (imported only when asked for) |
| ``*.onnx`` | ONNX Runtime, Ultralytics export format (1, 4 + classes, N) | ``onnxruntime`` |
| ``*.cfg``, ``*.weights`` or their folder | ONNX Runtime (converted graph) or OpenCV DNN | ``onnx`` extra / nothing |
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np

from processors.models import YOLO_FASTEST
from uav_values.detections import Detection

__all__ = ["DATA_DIR_ENV", "Backend", "Detection", "DetectorConfig", "find_data_dir", "load_backend"]
"""``Detection`` lives in :mod:`uav_values.detections`; the manual names it ``processors.detection.Detection``."""

logger = logging.getLogger(__name__)

DATA_DIR_ENV = "UAV_TUI_DATA_DIR"
"""Environment variable naming the shared data folder (the one holding ``aerial-tracking/``)."""


@dataclass(frozen=True)
class DetectorConfig:
    """Thresholds shared by all backends.

    Attributes:
        conf: minimum confidence.
        nms: IoU above which NMS suppresses the weaker of two boxes of one class.
        input_size: network input side in pixels; None = the model's own.
        classes: class ids to keep; None = all.
    """

    conf: float = 0.25
    nms: float = 0.45
    input_size: int | None = None
    classes: frozenset[int] | None = None


class Backend(Protocol):
    """What every backend provides."""

    names: list[str]
    """Class names, indexed by class id."""
    config: DetectorConfig
    """Thresholds and class filter; replaceable after construction."""

    def detect(self, frame: np.ndarray) -> list[Detection]:
        """Detections on a BGR uint8 frame, after confidence filter, class filter and NMS."""
        ...


def find_data_dir() -> Path:
    """The shared data folder: ``$UAV_TUI_DATA_DIR``, else the first ``shared/data`` found beside the
    repository or one of its parents (the repository sits beside ``shared/``).

    Raises:
        FileNotFoundError: naming the places searched and how to point at the folder.
    """
    env = os.environ.get(DATA_DIR_ENV)
    if env:
        if Path(env).is_dir():
            return Path(env)
        raise FileNotFoundError(f"{DATA_DIR_ENV}={env} is not a folder")
    repo = Path(__file__).resolve().parents[2]
    tried = []
    for parent in repo.parents:
        candidate = parent / "shared" / "data"
        tried.append(str(candidate))
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError(
        f"no shared data folder found (tried {', '.join(tried[:3])}, ...): set {DATA_DIR_ENV} to the folder "
        "holding aerial-tracking/"
    )


def load_backend(
    model: str | os.PathLike[str] | None, config: DetectorConfig, runtime: str | None = None
) -> Backend:
    """Open the backend that fits the model file (see the module table).

    Args:
        model: path to ``.pt``, ``.onnx``, ``.cfg``/``.weights`` or a folder with a Darknet pair;
            None = Yolo-Fastest 1.1, the Darknet model shipped in :mod:`processors.models`.
        config: thresholds and input size.
        runtime: for a Darknet model, ``"onnxruntime"`` or ``"opencv"``; None = ONNX Runtime when the ``onnx``
            extra is installed (:func:`processors.detection.darknet.default_runtime`).

    Raises:
        FileNotFoundError: the model file is missing.
        ValueError: the file type is not one of the supported ones, or a runtime is given for another kind of
            model, or is not one of the two.
        ImportError: the backend's library is not installed (the message says which extra).
    """
    path = Path(model).expanduser() if model is not None else YOLO_FASTEST
    if not path.exists():
        raise FileNotFoundError(f"detector model {path} does not exist")
    suffix = path.suffix.lower()
    if path.is_dir() or suffix in (".cfg", ".weights"):
        from processors.detection.darknet import DarknetBackend

        return DarknetBackend(path, config, runtime)
    if runtime is not None:
        raise ValueError(f"runtime={runtime!r} is for Darknet models; {path.name} has its own backend")
    if suffix == ".onnx":
        from processors.detection.onnx_runtime import OnnxBackend

        return OnnxBackend(path, config)
    if suffix == ".pt":
        from processors.detection.ultralytics_backend import UltralyticsBackend

        return UltralyticsBackend(path, config)
    raise ValueError(f"detector model {path}: expected .pt, .onnx, .cfg/.weights or a Darknet folder")
