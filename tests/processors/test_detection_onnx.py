"""The ONNX Runtime backend on a tiny ONNX model built here that emits known Ultralytics-format boxes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

onnx = pytest.importorskip("onnx", reason="the onnx package (dev extra) builds the test model")
pytest.importorskip("onnxruntime", reason="the onnx extra (onnxruntime) is not installed")

from onnx import TensorProto, helper, numpy_helper  # noqa: E402

from processors.detection import DetectorConfig, load_backend  # noqa: E402
from processors.detection.onnx_runtime import OnnxBackend  # noqa: E402
from processors.detection.postprocess import COCO_NAMES, letterbox  # noqa: E402
from processors.yolo_detector import YoloDetector  # noqa: E402

INPUT = 320
FRAME = (640, 480)  # letterbox: gain 0.5, 40 px of padding above and below
N_ANCHORS = 16


def _to_input(box: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    """Frame (x, y, w, h) -> network input (cx, cy, w, h) for the 640x480 -> 320x320 letterbox."""
    x, y, w, h = box
    return (x + w / 2) * 0.5, (y + h / 2) * 0.5 + 40, w * 0.5, h * 0.5


# (frame box, class, score): what the fake head emits, in frame pixels
EMITTED = [
    ((100.0, 80.0, 120.0, 200.0), 0, 0.90),  # person
    ((104.0, 84.0, 118.0, 196.0), 0, 0.60),  # same person, weaker: NMS removes it
    ((100.0, 80.0, 120.0, 200.0), 16, 0.70),  # a dog in the same place: per-class NMS keeps it
    ((400.0, 300.0, 60.0, 40.0), 15, 0.55),  # cat
    ((500.0, 100.0, 50.0, 50.0), 2, 0.10),  # below the confidence threshold
]


def _head_output(transposed: bool) -> np.ndarray:
    out = np.zeros((1, 84, N_ANCHORS), np.float32)
    for i, (box, cls, score) in enumerate(EMITTED):
        out[0, :4, i] = _to_input(box)
        out[0, 4 + cls, i] = score
        out[0, 4 + (cls + 1) % 80, i] = score / 3  # a weaker runner-up class
    return out.transpose(0, 2, 1).copy() if transposed else out


def _build_model(path: Path, transposed: bool = False, names: bool = True) -> Path:
    """images (1, 3, 320, 320) -> output0 = constant head output + 0 * mean(images)."""
    const = numpy_helper.from_array(_head_output(transposed), "head")
    shape = numpy_helper.from_array(np.array([1, 1, 1], np.int64), "shape")
    zero = numpy_helper.from_array(np.array(0.0, np.float32), "zero")
    nodes = [
        helper.make_node("ReduceMean", ["images"], ["mean"], keepdims=1),
        helper.make_node("Reshape", ["mean", "shape"], ["mean3"]),
        helper.make_node("Mul", ["mean3", "zero"], ["nothing"]),
        helper.make_node("Add", ["head", "nothing"], ["output0"]),
    ]
    out_shape = [1, N_ANCHORS, 84] if transposed else [1, 84, N_ANCHORS]
    graph = helper.make_graph(
        nodes,
        "fake_yolo_head",
        [helper.make_tensor_value_info("images", TensorProto.FLOAT, [1, 3, INPUT, INPUT])],
        [helper.make_tensor_value_info("output0", TensorProto.FLOAT, out_shape)],
        initializer=[const, shape, zero],
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    if names:
        meta = model.metadata_props.add()
        meta.key, meta.value = "names", repr(dict(enumerate(COCO_NAMES)))
    onnx.checker.check_model(model)
    onnx.save(model, path)
    return path


@pytest.fixture
def frame() -> np.ndarray:
    return np.full((FRAME[1], FRAME[0], 3), 80, np.uint8)


@pytest.mark.parametrize("transposed", [False, True], ids=["1x84xN", "1xNx84"])
def test_decode_letterbox_nms(tmp_path: Path, frame: np.ndarray, transposed: bool) -> None:
    backend = load_backend(_build_model(tmp_path / "m.onnx", transposed), DetectorConfig(conf=0.25, nms=0.45))
    assert isinstance(backend, OnnxBackend) and backend.size == (INPUT, INPUT)
    dets = backend.detect(frame)
    got = {(d.label, tuple(round(v, 1) for v in d.box), round(d.score, 2)) for d in dets}
    assert got == {
        ("person", (100.0, 80.0, 120.0, 200.0), 0.9),
        ("dog", (100.0, 80.0, 120.0, 200.0), 0.7),
        ("cat", (400.0, 300.0, 60.0, 40.0), 0.55),
    }
    assert [d.score for d in dets] == sorted((d.score for d in dets), reverse=True)


def test_class_filter_and_names_fallback(tmp_path: Path, frame: np.ndarray) -> None:
    model = _build_model(tmp_path / "m.onnx", names=False)
    det = YoloDetector(model=model, classes=["cat"])
    det.photo_processing(frame)
    assert [(d.label, d.class_id) for d in det.detections] == [("cat", 15)]


def test_letterbox_geometry() -> None:
    img, lb = letterbox(np.zeros((480, 640, 3), np.uint8), (320, 320))
    assert img.shape == (320, 320, 3)
    assert (lb.gain, lb.pad_x, lb.pad_y) == (0.5, 0.0, 40.0)
    assert (img[:40] == 114).all() and (img[280:] == 114).all() and (img[40:280] == 0).all()
