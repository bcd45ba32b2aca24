"""Darknet (``.cfg`` + ``.weights``) detector run with OpenCV DNN (OpenCV 4.x)."""

from __future__ import annotations

import configparser
import logging
from pathlib import Path

import cv2
import numpy as np

from processors.detection import DetectorConfig
from processors.detection.postprocess import COCO_NAMES, select
from uav_values.detections import Detection

logger = logging.getLogger(__name__)


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


def _net_size(cfg: Path) -> int:
    parser = configparser.ConfigParser(strict=False)
    text = cfg.read_text()
    parser.read_string(text[: text.index("\n[", 1)] if "\n[" in text[1:] else text)
    return int(parser.get("net", "width", fallback="416"))


class DarknetBackend:
    """YOLO Darknet model through ``cv2.dnn.readNetFromDarknet``.

    Class names come from ``coco.names`` (or ``<stem>.names``) beside the model, else COCO's.
    """

    def __init__(self, path: Path, config: DetectorConfig) -> None:
        cfg, weights = _model_pair(Path(path))
        self.net = cv2.dnn.readNetFromDarknet(str(cfg), str(weights))
        self.out_names = self.net.getUnconnectedOutLayersNames()
        self.config = config
        self.size = config.input_size or _net_size(cfg)
        names_file = next((p for p in (cfg.with_suffix(".names"), cfg.parent / "coco.names") if p.is_file()), None)
        self.names = names_file.read_text().splitlines() if names_file else list(COCO_NAMES)
        logger.info("DarknetBackend(%s): input %d, %d classes", cfg.name, self.size, len(self.names))

    def detect(self, frame: np.ndarray) -> list[Detection]:
        """Detections on a BGR frame (the network sees it resized to its square input)."""
        h, w = frame.shape[:2]
        blob = cv2.dnn.blobFromImage(frame, 1 / 255.0, (self.size, self.size), swapRB=True, crop=False)
        self.net.setInput(blob)
        rows = np.vstack([o.reshape(-1, o.shape[-1]) for o in self.net.forward(self.out_names)])
        # rows: cx, cy, w, h (0..1 of the input), objectness, class scores (already x objectness)
        centres = rows[:, :4] * np.array([w, h, w, h], np.float32)
        return select(centres, rows[:, 5:], self.config, self.names, (w, h))
