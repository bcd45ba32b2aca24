"""YOLO object detection (Ultralytics .pt, ONNX Runtime, Darknet on ONNX Runtime or OpenCV DNN) with an optional
follow."""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np

from processors.detection import DetectorConfig, load_backend
from processors.detection.flow import shift_boxes
from processors.detections import MAX_DETECTIONS
from processors.detector_help import iou
from processors.frame_telemetry import frame_time_s
from processors.steering import Steering, Vector, as_box, draw_target
from uav_values.box import Box
from uav_values.detections import Detection

logger = logging.getLogger(__name__)

_DETECT_EVERY = {"fast": 3, "paper": 1}
"""Detector keyframe interval per mode; in between, boxes move with optical flow."""


class YoloDetector:
    """Detect objects with a YOLO model; optionally follow one of them.

    The backend is chosen by the model file: ``.pt`` Ultralytics (the ``yolo`` extra), ``.onnx``
    exported by Ultralytics (ONNX Runtime), ``.cfg``/``.weights`` Darknet (ONNX Runtime on the converted graph, or
    OpenCV DNN: ``runtime``). Default: the Yolo-Fastest 1.1 Darknet model shipped with the package. Detections are
    drawn on the frame and, at most every ``save_interval_s``, the drawn frame is saved through ``tmMgr`` with the
    detection count and labels. ``detections`` is the contract's optional attribute: the platform records each one
    (detections.csv), geo-locates it and shows the most confident; at most ``MAX_DETECTIONS``, most confident first.

    Follow: ``catch_cmd(roi)`` picks the detection overlapping the ROI most (or, when none
    overlaps, the first one of a later keyframe that does); ``follow="<class name>"`` picks the most
    confident detection of that class whenever nothing is followed. The followed object is matched
    from keyframe to keyframe by class and overlap.

    Vector: the tracker's steering (processors.steering): body-frame m/s (vx forward, vy right)
    that centres the followed object (``camera="down"``) or keeps it centred and at its selection
    size (``camera="forward"``), ``t`` = ``vector_t`` s. ``getPreparedVector`` returns None when
    nothing is followed or the followed object has not been seen for ``max_lost`` keyframes.

    Operator buttons:
        F1: stop following.
        F2: follow the most confident detection (after the class filter).
        F3: gain x 1.25.
        F4: gain / 1.25.

    Args:
        model: model file or Darknet folder; None = the shipped ``yolo-fastest-1.1``.
        conf, nms: confidence and NMS IoU thresholds.
        input_size: network input side; None = the model's own.
        classes: class names or ids to keep; None = all.
        follow: class name to follow automatically; None = only on operator selection.
        mode: "fast" (detector every 3rd frame, optical flow in between) or "paper" (every frame).
        detect_every: override the mode's keyframe interval.
        camera, gain, dead_band, max_speed, vector_t: steering.
        max_lost: keyframes without the followed object before it counts as lost.
        save_interval_s: minimum time between saved detection frames; 0 saves every keyframe
            with detections.
        runtime: what runs a Darknet model: ``"onnxruntime"`` (the ``onnx`` extra) or ``"opencv"`` (OpenCV DNN);
            None = ONNX Runtime when the ``onnx`` extra is installed, else OpenCV DNN.
    """

    def __init__(
        self,
        model: str | Path | None = None,
        conf: float = 0.25,
        nms: float = 0.45,
        input_size: int | None = None,
        classes: Sequence[str | int] | None = None,
        follow: str | None = None,
        mode: str = "fast",
        detect_every: int | None = None,
        camera: str = "down",
        gain: float = 0.8,
        dead_band: float = 0.05,
        max_speed: float = 1.0,
        vector_t: float = 0.5,
        max_lost: int = 5,
        save_interval_s: float = 1.0,
        runtime: str | None = None,
    ) -> None:
        if mode not in _DETECT_EVERY:
            raise ValueError(f"mode must be one of {sorted(_DETECT_EVERY)}, got {mode!r}")
        if input_size is not None and (input_size < 32 or input_size % 32):
            raise ValueError(f"input_size must be a multiple of 32 (e.g. 320, 416, 640), got {input_size}")
        self.tmMgr = None
        self.mode = mode
        self.backend = load_backend(model, DetectorConfig(conf, nms, input_size), runtime)
        names = self.backend.names
        if classes is not None:
            ids = frozenset(c if isinstance(c, int) else self._class_id(c) for c in classes)
            self.backend.config = dataclasses.replace(self.backend.config, classes=ids)
        self.follow_class = self._class_id(follow) if follow is not None else None
        self.detect_every = max(int(detect_every or _DETECT_EVERY[mode]), 1)
        self.steering = Steering(camera, gain, dead_band, max_speed, vector_t)
        self.max_lost = max_lost
        self.save_interval_s = save_interval_s
        self.detections: list[Detection] = []
        """Detections of the newest frame (moved by optical flow between keyframes), most confident first, at most
        ``MAX_DETECTIONS``: the contract's ``detections`` attribute (box, label, score each)."""
        self.followed: Detection | None = None
        """The object being followed, None when nothing is."""
        self._pending_roi: tuple[float, float, float, float] | None = None
        self._ref_height = 0.0
        self._missed = 0
        self._frame_no = 0
        self._prev_gray: np.ndarray | None = None
        self._last_save = -float("inf")
        self._vector: Vector | None = None
        logger.info("YoloDetector: %s backend, %d classes", type(self.backend).__name__, len(names))

    def _class_id(self, name: str) -> int:
        try:
            return self.backend.names.index(name)
        except ValueError:
            raise ValueError(f"class {name!r} is not one of the model's classes") from None

    # ---- contract -------------------------------------------------------------------------------
    def photo_processing(self, frame: np.ndarray) -> None:
        """Detect (keyframe) or move the last detections (between keyframes); draw; maybe save."""
        keyframe = self._frame_no % self.detect_every == 0
        self._frame_no += 1
        gray = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY) if self.detect_every > 1 else None
        if keyframe:
            self.detections = self.backend.detect(frame)[:MAX_DETECTIONS]  # sorted by score
            self._associate()
        else:
            self._propagate(gray)
        self._prev_gray = gray
        size = (frame.shape[1], frame.shape[0])
        following = self.followed if self._missed == 0 else None
        self._vector = self.steering.vector(following.box, size, self._ref_height) if following is not None else None
        self._draw(frame)
        if keyframe and self.detections and self.tmMgr is not None:
            now = frame_time_s(self.tmMgr)  # the frame's capture time: a replay saves the same frames
            if now - self._last_save >= self.save_interval_s:
                self._last_save = now
                labels = ";".join(f"{d.label}:{d.score:.2f}" for d in self.detections)
                self.tmMgr.save(frame, detections=len(self.detections), labels=labels)

    def catch_cmd(self, roi: tuple[int, int, int, int]) -> None:
        """Follow the detection that overlaps ``roi`` (x, y, w, h, frame pixels) the most."""
        self._pending_roi = as_box(roi)
        self.followed = None
        self._pick_from_roi()

    def customize_processing(self, id: int) -> None:  # noqa: A002 - published name
        """F1 stop following, F2 follow the most confident detection, F3 gain up, F4 gain down."""
        if id == 1:
            self.followed, self._pending_roi, self.follow_class, self._vector = None, None, None, None
        elif id == 2 and self.detections:
            self._start_following(self.detections[0])
        elif id == 3:
            self.steering.scale_gain(1.25)
        elif id == 4:
            self.steering.scale_gain(1 / 1.25)

    def getPreparedVector(self) -> Vector | None:
        """(vx, vy, t) towards the followed object, None when nothing is followed or it is lost."""
        return self._vector

    @property
    def box(self) -> Box | None:
        """The followed detection's box (x, y, w, h, frame pixels); None when nothing is followed or it is
        missing from the latest keyframe."""
        return self.followed.box if self.followed is not None and self._missed == 0 else None

    # ---- follow ---------------------------------------------------------------------------------
    def _start_following(self, det: Detection) -> None:
        self.followed, self._pending_roi, self._missed = det, None, 0
        self._ref_height = det.box[3]
        logger.info("YoloDetector: following %s (%.2f) at %s", det.label, det.score, det.box)

    def _pick_from_roi(self) -> None:
        roi = self._pending_roi
        if roi is None:
            return
        best = max(self.detections, key=lambda d: iou(d.box, roi), default=None)
        if best is not None and iou(best.box, roi) > 0.05:
            self._start_following(best)

    def _associate(self) -> None:
        """Match the followed object to this keyframe's detections (same class, best overlap)."""
        if self._pending_roi is not None:
            self._pick_from_roi()
        elif (followed := self.followed) is not None:
            same = [d for d in self.detections if d.class_id == followed.class_id]
            best = max(same, key=lambda d: iou(d.box, followed.box), default=None)
            if best is not None and iou(best.box, followed.box) > 0.1:
                self.followed, self._missed = best, 0
            else:
                self._missed += 1
                if self._missed >= self.max_lost:
                    logger.info("YoloDetector: lost %s", followed.label)
                    self.followed = None
        if self.followed is None and self.follow_class is not None:
            match = [d for d in self.detections if d.class_id == self.follow_class]
            if match:
                self._start_following(match[0])

    def _propagate(self, gray: np.ndarray | None) -> None:
        """Between keyframes: move the detections (and the followed box) with optical flow."""
        if gray is None or self._prev_gray is None:
            return
        boxes = [d.box for d in self.detections]
        if self.followed is not None:
            boxes.append(self.followed.box)
        moved = shift_boxes(self._prev_gray, gray, boxes)
        self.detections = [
            dataclasses.replace(d, box=b) for d, b in zip(self.detections, moved, strict=False) if b is not None
        ]
        if self.followed is not None and moved[-1] is not None:
            self.followed = dataclasses.replace(self.followed, box=moved[-1])

    def _draw(self, frame: np.ndarray) -> None:
        for det in self.detections:
            x, y, w, h = (int(round(v)) for v in det.box)
            cv2.rectangle(frame, (x, y), (x + w, y + h), (255, 160, 0), 1)
            cv2.putText(
                frame,
                f"{det.label} {det.score:.2f}",
                (x, max(12, y - 3)),
                cv2.FONT_HERSHEY_SIMPLEX,
                0.45,
                (255, 160, 0),
                1,
                cv2.LINE_AA,
            )
        if self.followed is not None:
            draw_target(frame, self.followed.box, self._vector, (0, 255, 0), f"follow {self.followed.label}")
