"""Letterbox, YOLO output decoding and NMS shared by the ONNX and Darknet backends."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from processors.detection import DetectorConfig
from uav_values.detections import Detection

COCO_NAMES = [
    "person",
    "bicycle",
    "car",
    "motorcycle",
    "airplane",
    "bus",
    "train",
    "truck",
    "boat",
    "traffic light",
    "fire hydrant",
    "stop sign",
    "parking meter",
    "bench",
    "bird",
    "cat",
    "dog",
    "horse",
    "sheep",
    "cow",
    "elephant",
    "bear",
    "zebra",
    "giraffe",
    "backpack",
    "umbrella",
    "handbag",
    "tie",
    "suitcase",
    "frisbee",
    "skis",
    "snowboard",
    "sports ball",
    "kite",
    "baseball bat",
    "baseball glove",
    "skateboard",
    "surfboard",
    "tennis racket",
    "bottle",
    "wine glass",
    "cup",
    "fork",
    "knife",
    "spoon",
    "bowl",
    "banana",
    "apple",
    "sandwich",
    "orange",
    "broccoli",
    "carrot",
    "hot dog",
    "pizza",
    "donut",
    "cake",
    "chair",
    "couch",
    "potted plant",
    "bed",
    "dining table",
    "toilet",
    "tv",
    "laptop",
    "mouse",
    "remote",
    "keyboard",
    "cell phone",
    "microwave",
    "oven",
    "toaster",
    "sink",
    "refrigerator",
    "book",
    "clock",
    "vase",
    "scissors",
    "teddy bear",
    "hair drier",
    "toothbrush",
]
"""The 80 COCO class names in Ultralytics order, used when a model carries none."""


@dataclass(frozen=True)
class Letterbox:
    """How a frame was resized and padded into the network input: ``input = frame * gain + pad``."""

    gain: float
    pad_x: float
    pad_y: float

    def to_frame(self, xywh: np.ndarray) -> np.ndarray:
        """Map (x, y, w, h) boxes from input pixels back to frame pixels."""
        out = xywh.astype(np.float32).copy()
        out[:, 0] = (out[:, 0] - self.pad_x) / self.gain
        out[:, 1] = (out[:, 1] - self.pad_y) / self.gain
        out[:, 2:] /= self.gain
        return out


def letterbox(frame: np.ndarray, size: tuple[int, int], fill: int = 114) -> tuple[np.ndarray, Letterbox]:
    """Resize keeping the aspect ratio and pad to ``size`` = (width, height), Ultralytics-style."""
    h, w = frame.shape[:2]
    tw, th = size
    gain = min(tw / w, th / h)
    nw, nh = int(round(w * gain)), int(round(h * gain))
    dw, dh = (tw - nw) / 2.0, (th - nh) / 2.0
    resized = cv2.resize(frame, (nw, nh), interpolation=cv2.INTER_LINEAR) if (nw, nh) != (w, h) else frame
    top, left = int(round(dh - 0.1)), int(round(dw - 0.1))
    out = cv2.copyMakeBorder(
        resized, top, th - nh - top, left, tw - nw - left, cv2.BORDER_CONSTANT, value=(fill, fill, fill)
    )
    return out, Letterbox(gain, float(left), float(top))


def select(
    centres: np.ndarray,
    scores: np.ndarray,
    config: DetectorConfig,
    names: list[str],
    frame_size: tuple[int, int],
) -> list[Detection]:
    """Confidence and class filter, per-class NMS, clip to the frame.

    Args:
        centres: N x 4 (cx, cy, w, h) in frame pixels.
        scores: N x C class scores.
        config: thresholds and class filter.
        names: class names.
        frame_size: (width, height).
    """
    if len(centres) == 0:
        return []
    class_ids = scores.argmax(axis=1)
    best = scores[np.arange(len(scores)), class_ids]
    keep = best >= config.conf
    if config.classes is not None:
        keep &= np.isin(class_ids, list(config.classes))
    centres, best, class_ids = centres[keep], best[keep], class_ids[keep]
    if len(centres) == 0:
        return []
    xywh = np.column_stack([centres[:, 0] - centres[:, 2] / 2, centres[:, 1] - centres[:, 3] / 2, centres[:, 2:]])
    idx = cv2.dnn.NMSBoxesBatched(
        xywh.tolist(), best.astype(float).tolist(), class_ids.tolist(), config.conf, config.nms
    )
    w, h = frame_size
    out = []
    for i in np.array(idx, dtype=int).reshape(-1):
        x0, y0 = max(float(xywh[i, 0]), 0.0), max(float(xywh[i, 1]), 0.0)
        x1, y1 = min(float(xywh[i, 0] + xywh[i, 2]), w), min(float(xywh[i, 1] + xywh[i, 3]), h)
        cid = int(class_ids[i])
        label = names[cid] if cid < len(names) else f"class {cid}"
        out.append(Detection((x0, y0, x1 - x0, y1 - y0), float(best[i]), cid, label))
    return sorted(out, key=lambda d: -d.score)
