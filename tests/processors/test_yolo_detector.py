"""YoloDetector with the real Darknet model on real photographs; follow; errors."""

from __future__ import annotations

import importlib.util

import cv2
import numpy as np
import pytest
from skimage import data

from processors.detection import DATA_DIR_ENV, find_data_dir
from processors.synthetic import ASTRONAUT_PERSON, CHELSEA_CAT, detection_sequence, iou
from processors.yolo_detector import YoloDetector

PERSON = ASTRONAUT_PERSON
CAT = CHELSEA_CAT


def _bgr(rgb: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR)


@pytest.fixture(scope="module")
def astronaut() -> np.ndarray:
    return _bgr(data.astronaut())


@pytest.fixture(scope="module")
def chelsea() -> np.ndarray:
    return _bgr(data.chelsea())


@pytest.mark.parametrize(
    ("image", "label", "truth"),
    [("astronaut", "person", PERSON), ("chelsea", "cat", CAT)],
    ids=["person", "cat"],
)
def test_darknet_finds_the_object(image: str, label: str, truth: tuple, request: pytest.FixtureRequest) -> None:
    frame = request.getfixturevalue(image)
    det = YoloDetector(mode="paper")
    det.photo_processing(frame.copy())
    best = det.detections[0]
    assert best.label == label and best.score >= 0.4
    assert iou(best.box, truth) >= 0.6


def test_class_filter_and_overlay_and_save(astronaut: np.ndarray, tm_mgr) -> None:
    det = YoloDetector(classes=["cat"])
    det.photo_processing(astronaut.copy())
    assert det.detections == []
    det = YoloDetector(classes=["person"], save_interval_s=3600)
    det.tmMgr = tm_mgr
    for _ in range(4):  # keyframes 0 and 3 have detections; the rate limit saves one
        frame = astronaut.copy()
        det.photo_processing(frame)
    assert (frame != astronaut).any()  # drawn in place
    assert len(tm_mgr.saved) == 1
    assert tm_mgr.saved[0][1]["detections"] == 1 and tm_mgr.saved[0][1]["labels"].startswith("person:")


def test_catch_cmd_follows_the_selected_detection(astronaut: np.ndarray) -> None:
    det = YoloDetector()
    det.photo_processing(astronaut.copy())
    assert det.getPreparedVector() is None and det.box is None  # detections, but nothing followed
    det.catch_cmd((150, 80, 100, 100))  # a box around the face
    # the object sits left of the 512-wide frame's centre and low: fly left and back
    shifted = np.roll(astronaut, -80, axis=1)
    for _ in range(3):
        det.photo_processing(shifted.copy())
    assert det.followed is not None and det.followed.label == "person"
    assert det.box == det.followed.box  # what it follows is what it reports
    vx, vy, t = det.getPreparedVector()
    cx = det.followed.box[0] + det.followed.box[2] / 2
    assert np.sign(vy) == np.sign(cx - 256) != 0
    assert 0 < t <= 2
    det.customize_processing(1)
    det.photo_processing(shifted.copy())
    assert det.getPreparedVector() is None


def test_follow_by_class_name_and_lost_after_max_lost(chelsea: np.ndarray) -> None:
    det = YoloDetector(follow="cat", detect_every=1, max_lost=2)
    det.photo_processing(chelsea.copy())
    assert det.followed is not None and det.getPreparedVector() is not None
    blank = np.full_like(chelsea, 90)
    det.photo_processing(blank)
    assert det.getPreparedVector() is None and det.box is None  # not seen on this keyframe
    det.follow_class = None
    det.photo_processing(blank)
    assert det.followed is None


def test_fast_mode_moves_boxes_between_keyframes(astronaut: np.ndarray) -> None:
    det = YoloDetector(mode="fast")
    assert det.detect_every == 3
    det.photo_processing(astronaut.copy())
    x0 = det.detections[0].box[0]
    det.photo_processing(np.roll(astronaut, 12, axis=1))  # not a keyframe: optical flow
    assert det.detections[0].box[0] == pytest.approx(x0 + 12, abs=2)


def test_model_errors_are_explicit(tmp_path, monkeypatch: pytest.MonkeyPatch) -> None:
    with pytest.raises(FileNotFoundError, match="does not exist"):
        YoloDetector(model=tmp_path / "missing.onnx")
    (tmp_path / "m.tflite").write_bytes(b"x")
    with pytest.raises(ValueError, match=r"expected \.pt, \.onnx"):
        YoloDetector(model=tmp_path / "m.tflite")
    with pytest.raises(ValueError, match="multiple of 32"):
        YoloDetector(input_size=300)
    with pytest.raises(ValueError, match="not one of the model's classes"):
        YoloDetector(follow="unicorn")
    monkeypatch.setenv(DATA_DIR_ENV, str(tmp_path / "nowhere"))
    with pytest.raises(FileNotFoundError, match=DATA_DIR_ENV):
        find_data_dir()


@pytest.mark.skipif(importlib.util.find_spec("ultralytics") is not None, reason="ultralytics is installed")
def test_pt_model_without_ultralytics_says_which_extra(tmp_path) -> None:
    (tmp_path / "yolov8n.pt").write_bytes(b"not a model")
    with pytest.raises(ImportError, match=r"uav-tui\[yolo\]"):
        YoloDetector(model=tmp_path / "yolov8n.pt")


def test_ultralytics_backend(tmp_path, astronaut: np.ndarray) -> None:
    ultralytics = pytest.importorskip("ultralytics", reason="the yolo extra (ultralytics) is not installed")
    model = ultralytics.YOLO("yolov8n.yaml")  # built from its definition: random weights, no download
    model.save(str(tmp_path / "random.pt"))
    det = YoloDetector(model=tmp_path / "random.pt", conf=0.0, input_size=160)
    det.photo_processing(astronaut.copy())
    assert all(0 <= d.class_id < 80 and d.box[2] >= 0 for d in det.detections)


@pytest.mark.parametrize("mode", ["fast", "paper"])
def test_follows_a_moving_person(mode: str) -> None:
    frames, truth = detection_sequence((320, 240), 12)
    det = YoloDetector(mode=mode, follow="person")
    ious = []
    for frame, box in zip(frames, truth, strict=True):
        det.photo_processing(frame.copy())
        ious.append(iou(det.followed.box if det.followed else None, box))
    assert np.mean(ious) >= 0.5
