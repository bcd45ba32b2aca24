"""Darknet (``.cfg`` + ``.weights``) detector, run with ONNX Runtime or OpenCV DNN: the same rows, one postprocess."""

from __future__ import annotations

import importlib.util
import logging
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np

from processors.detection import DetectorConfig
from processors.detection.darknet_cfg import read_cfg
from processors.detection.postprocess import COCO_NAMES, select
from uav_values.detections import Detection

logger = logging.getLogger(__name__)

RUNTIMES = ("onnxruntime", "opencv")
"""What runs the network: ONNX Runtime on the converted graph (:mod:`processors.detection.darknet_onnx`; its MLAS
kernels have NEON on ARM and AVX here), or OpenCV DNN's Darknet reader (needs nothing extra)."""

Rows = Callable[[np.ndarray], np.ndarray]
"""The network on a blob (1, 3, size, size): its rows (N, 5 + classes), as :mod:`darknet_onnx` describes them."""


def default_runtime() -> str:
    """``"onnxruntime"`` when it and ``onnx`` are installed (uav-tui's dependencies), else ``"opencv"``.

    ONNX Runtime takes about half OpenCV DNN's CPU a detection (``scripts/results/detection.json``).
    """
    installed = all(importlib.util.find_spec(name) is not None for name in ("onnxruntime", "onnx"))
    return "onnxruntime" if installed else "opencv"


def _model_pair(path: Path) -> tuple[Path, Path]:
    if path.is_dir():
        cfgs = sorted(path.glob("*.cfg"))
        if len(cfgs) != 1:
            raise FileNotFoundError(f"{path}: expected exactly one .cfg file, found {len(cfgs)}")
        path = cfgs[0]
    cfg, weights = path.with_suffix(".cfg"), path.with_suffix(".weights")
    for p in (cfg, weights):
        if not p.is_file():
            raise FileNotFoundError(f"Darknet model needs {cfg.name} and {weights.name} side by side: {p} missing")
    return cfg, weights


def _opencv_rows(cfg: Path, weights: Path) -> Rows:
    net = cv2.dnn.readNetFromDarknet(str(cfg), str(weights))
    out_names = net.getUnconnectedOutLayersNames()

    def rows(blob: np.ndarray) -> np.ndarray:
        net.setInput(blob)
        return np.vstack([o.reshape(-1, o.shape[-1]) for o in net.forward(out_names)])

    return rows


def _onnxruntime_rows(cfg: Path, weights: Path, size: int) -> Rows:
    from processors.detection.darknet_cache import darknet_onnx_model
    from processors.detection.onnx_runtime import open_session

    session = open_session(darknet_onnx_model(cfg, weights, size), "runtime='onnxruntime'")

    def rows(blob: np.ndarray) -> np.ndarray:
        return np.asarray(session.run(["rows"], {"images": blob})[0])

    return rows


class DarknetBackend:
    """YOLO Darknet model through ONNX Runtime or OpenCV DNN.

    Class names come from ``coco.names`` (or ``<stem>.names``) beside the model, else COCO's.

    Args:
        path: the ``.cfg``, the ``.weights`` or their folder.
        config: thresholds; ``input_size`` None = the ``.cfg``'s width.
        runtime: one of :data:`RUNTIMES`; None = :func:`default_runtime`.

    Raises:
        ValueError: an unknown runtime.
        ImportError: ``runtime="onnxruntime"`` without the ``onnx`` extra (the message says so).
    """

    def __init__(self, path: Path, config: DetectorConfig, runtime: str | None = None) -> None:
        cfg, weights = _model_pair(Path(path))
        if runtime is not None and runtime not in RUNTIMES:
            raise ValueError(f"runtime must be one of {', '.join(RUNTIMES)}, got {runtime!r}")
        self.runtime = runtime or default_runtime()
        self.config = config
        self.size = config.input_size or read_cfg(cfg)[0].get_int("width", 416)
        if self.runtime == "opencv":
            self._rows = _opencv_rows(cfg, weights)
        else:
            self._rows = _onnxruntime_rows(cfg, weights, self.size)
        names_file = next((p for p in (cfg.with_suffix(".names"), cfg.parent / "coco.names") if p.is_file()), None)
        self.names = names_file.read_text().splitlines() if names_file else list(COCO_NAMES)
        logger.info("DarknetBackend(%s): %s, input %d, %d classes", cfg.name, self.runtime, self.size, len(self.names))

    def detect(self, frame: np.ndarray) -> list[Detection]:
        """Detections on a BGR frame (the network sees it resized to its square input)."""
        h, w = frame.shape[:2]
        blob = cv2.dnn.blobFromImage(frame, 1 / 255.0, (self.size, self.size), swapRB=True, crop=False)
        rows = self._rows(blob)
        # rows: cx, cy, w, h (0..1 of the input), objectness, class scores (already x objectness)
        centres = rows[:, :4] * np.array([w, h, w, h], np.float32)
        return select(centres, rows[:, 5:], self.config, self.names, (w, h))
