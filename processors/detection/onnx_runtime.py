"""Ultralytics-exported ONNX detector (YOLOv8/v11 head) run with ONNX Runtime, no PyTorch."""

from __future__ import annotations

import ast
import logging
import os
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from processors.detection import DetectorConfig
from processors.detection.postprocess import COCO_NAMES, letterbox, select
from uav_values.detections import Detection

logger = logging.getLogger(__name__)

INSTALL = "pip install onnxruntime onnx (uav-tui's own dependencies: bash scripts/setup.sh installs them)"
"""What installs ONNX Runtime and onnx where they are missing (a venv made by hand)."""

THREADS_ENV = "UAV_TUI_ONNX_THREADS"
"""When set (``uav-tui eval --threads N`` sets it), the threads of each ONNX Runtime session (else its default)."""


def decode(output: np.ndarray, n_classes: int) -> tuple[np.ndarray, np.ndarray]:
    """Split an Ultralytics head output into boxes and scores.

    Args:
        output: (1, 4 + n_classes, N) - or its transpose (1, N, 4 + n_classes) - with rows
            cx, cy, w, h (input pixels) then one score per class (no objectness).
        n_classes: number of classes.

    Returns:
        (N x 4 centres cx, cy, w, h in input pixels, N x n_classes scores).
    """
    out = output[0]
    if out.shape[0] != 4 + n_classes:
        out = out.T
    if out.shape[0] != 4 + n_classes:
        raise ValueError(f"ONNX output shape {output.shape} does not fit 4 + {n_classes} classes")
    return out[:4].T, out[4:].T


def open_session(model: str | bytes, user: str) -> Any:
    """An ``onnxruntime.InferenceSession`` on the CPU for a model file (or its bytes) whose threads sleep between runs.

    Args:
        model: the ``.onnx`` file's path, or the serialised model.
        user: who needs it, for the error (``"the .onnx backend"``).

    Raises:
        ImportError: onnxruntime is not installed; the message says how to install it.
    """
    try:
        import onnxruntime as ort
    except ImportError as exc:
        raise ImportError(f"{user} needs onnxruntime: {INSTALL}") from exc
    options = ort.SessionOptions()
    # Its threads sleep between runs instead of spinning: the camera decodes on the same cores meanwhile.
    options.add_session_config_entry("session.intra_op.allow_spinning", "0")
    if os.environ.get(THREADS_ENV, "").isdigit():
        options.intra_op_num_threads = int(os.environ[THREADS_ENV])
    return ort.InferenceSession(model, options, providers=["CPUExecutionProvider"])


class OnnxBackend:
    """ONNX Runtime session on a model exported with ``yolo export format=onnx``.

    Input: letterboxed RGB, 0..1, NCHW; class names from the model's ``names`` metadata (written by
    Ultralytics), else COCO's.
    """

    def __init__(self, path: Path, config: DetectorConfig) -> None:
        self.session = open_session(str(path), "the .onnx backend")
        inp = self.session.get_inputs()[0]
        self.input_name = inp.name
        h, w = inp.shape[2:4]
        fixed = isinstance(h, int) and isinstance(w, int)
        if config.input_size and fixed and (h, w) != (config.input_size,) * 2:
            logger.warning("OnnxBackend(%s): model input is fixed at %dx%d, input_size ignored", path.name, w, h)
        self.size = (w, h) if fixed else (config.input_size or 640,) * 2
        meta = self.session.get_modelmeta().custom_metadata_map
        names = ast.literal_eval(meta["names"]) if "names" in meta else None
        self.names = [names[i] for i in sorted(names)] if isinstance(names, dict) else list(COCO_NAMES)
        self.config = config
        logger.info("OnnxBackend(%s): input %dx%d, %d classes", path.name, *self.size, len(self.names))

    def detect(self, frame: np.ndarray) -> list[Detection]:
        """Letterbox, run, decode, undo the letterbox, filter and NMS."""
        img, lb = letterbox(frame, self.size)
        blob = cv2.cvtColor(img, cv2.COLOR_BGR2RGB).transpose(2, 0, 1)[None].astype(np.float32) / 255.0
        (output,) = self.session.run(None, {self.input_name: blob})[:1]
        centres, scores = decode(output, len(self.names))
        centres = lb.to_frame(centres)  # cx, cy scale like x, y; w, h by the gain
        return select(centres, scores, self.config, self.names, (frame.shape[1], frame.shape[0]))
