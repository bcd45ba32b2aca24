"""Models that ship with the package (package data, each folder with its licence and a README naming its source).

Installed with ``pip install``, so a drone with no network and no data folder has them:

* ``nanotrack-v2/``: NanoTrack v2, the two ONNX files ``cv2.TrackerNano`` loads (Apache-2.0);
* ``yolo-fastest-1.1/``: Yolo-Fastest 1.1, a Darknet COCO detector (public domain).
"""

from __future__ import annotations

from pathlib import Path

import cv2

MODELS = Path(__file__).resolve().parent
"""This folder."""

NANOTRACK_V2 = MODELS / "nanotrack-v2"
"""NanoTrack v2's backbone and neck/head ONNX files."""

YOLO_FASTEST = MODELS / "yolo-fastest-1.1"
"""Yolo-Fastest 1.1: ``.cfg``, ``.weights`` and ``coco.names`` (a Darknet folder)."""


def nanotrack_files() -> dict[str, str]:
    """``TrackerNano_Params`` fields naming the shipped NanoTrack v2 models: ``backbone`` and ``neckhead``."""
    return {"backbone": str(NANOTRACK_V2 / "nanotrack_backbone_sim.onnx"),
            "neckhead": str(NANOTRACK_V2 / "nanotrack_head_sim.onnx")}


def create_nanotrack() -> cv2.TrackerNano:
    """A new ``cv2.TrackerNano`` on the shipped NanoTrack v2 models (OpenCV's default backend, CPU)."""
    params = cv2.TrackerNano.Params()
    for key, value in nanotrack_files().items():
        setattr(params, key, value)
    return cv2.TrackerNano.create(params)
