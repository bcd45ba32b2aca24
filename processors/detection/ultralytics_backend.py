"""Ultralytics (PyTorch ``.pt``) detector: the ``yolo`` extra, imported only when such a model is used."""

from __future__ import annotations

import logging
import os
from pathlib import Path
from typing import Any

import numpy as np

from processors.detection import DetectorConfig
from uav_values.detections import Detection

logger = logging.getLogger(__name__)


class UltralyticsBackend:
    """``ultralytics.YOLO(model).predict`` with the configured thresholds; never downloads anything."""

    def __init__(self, path: Path, config: DetectorConfig) -> None:
        os.environ.setdefault("YOLO_OFFLINE", "1")  # no update checks / asset downloads at run time
        try:
            from ultralytics import YOLO
        except ImportError as exc:
            raise ImportError(
                "the .pt backend needs Ultralytics: pip install 'uav-tui[yolo]', then run "
                "scripts/fix_opencv.sh (ultralytics replaces opencv-contrib, which CSRT needs); "
                "or export the model to .onnx and use the ONNX Runtime backend"
            ) from exc
        self.model = YOLO(str(path))
        self.names = [self.model.names[i] for i in sorted(self.model.names)]
        self.config = config
        logger.info("UltralyticsBackend(%s): %d classes", path.name, len(self.names))

    def detect(self, frame: np.ndarray) -> list[Detection]:
        """Run ``predict`` on the BGR frame and convert its boxes."""
        cfg = self.config
        kwargs: dict[str, Any] = {"conf": cfg.conf, "iou": cfg.nms, "verbose": False}
        if cfg.input_size:
            kwargs["imgsz"] = cfg.input_size
        if cfg.classes is not None:
            kwargs["classes"] = sorted(cfg.classes)
        boxes = self.model.predict(frame, **kwargs)[0].boxes
        xyxy = boxes.xyxy.cpu().numpy()
        scores = boxes.conf.cpu().numpy()
        ids = boxes.cls.cpu().numpy().astype(int)
        out = [
            Detection((float(x0), float(y0), float(x1 - x0), float(y1 - y0)), float(s), int(c), self.names[c])
            for (x0, y0, x1, y1), s, c in zip(xyxy, scores, ids, strict=True)
        ]
        return sorted(out, key=lambda d: -d.score)
