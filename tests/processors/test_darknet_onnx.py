"""The shipped Yolo-Fastest converted to ONNX and run by ONNX Runtime, against OpenCV DNN's Darknet reader, on real
aerial video; the ``runtime`` switch through the processor loader; what a missing package says."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

pytest.importorskip("onnx", reason="onnx is not installed")
pytest.importorskip("onnxruntime", reason="the onnx extra (onnxruntime) is not installed")

from processors import load_processor  # noqa: E402
from processors.detection import DetectorConfig, load_backend  # noqa: E402
from processors.detection.darknet_cache import cache_folder, darknet_onnx_model  # noqa: E402
from processors.detection.darknet_onnx import darknet_to_onnx  # noqa: E402
from processors.detection.onnx_runtime import INSTALL, open_session  # noqa: E402
from processors.errors import ProcessorLoadError  # noqa: E402
from processors.models import YOLO_FASTEST  # noqa: E402
from processors.yolo_detector import YoloDetector  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
CFG, WEIGHTS = YOLO_FASTEST / "yolo-fastest-1.1.cfg", YOLO_FASTEST / "yolo-fastest-1.1.weights"
FRAMES = {"uavdt-S1606": (0, 60), "dtb70-Animal3": (30,), "uav123_10fps-person9": (0, 45), "uav123_10fps-boat5": (40,)}
"""Sequence -> frame numbers: cars at a crossroads, a herd, two people, a boat."""


@pytest.fixture(scope="module")
def frames(aerial_tracking: Path) -> list[np.ndarray]:
    """The frames of :data:`FRAMES`, at 640x480."""
    out = []
    for name, numbers in FRAMES.items():
        capture = cv2.VideoCapture(str(aerial_tracking / name / "video.mp4"))
        for number in range(max(numbers) + 1):
            ok, frame = capture.read()
            assert ok, f"{name} ends before frame {number}"
            if number in numbers:
                out.append(cv2.resize(frame, (640, 480), interpolation=cv2.INTER_AREA))
        capture.release()
    return out


@pytest.fixture
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty cache folder of the user's (``$XDG_CACHE_HOME``), for this test alone."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    return cache_folder()


@pytest.mark.parametrize("size", [320, 416], ids=["cfg-320", "input-416"])
def test_the_graph_gives_opencvs_rows_on_real_frames(frames: list[np.ndarray], size: int) -> None:
    session = open_session(darknet_to_onnx(CFG, WEIGHTS, size).SerializeToString(), "the test")
    net = cv2.dnn.readNetFromDarknet(str(CFG), str(WEIGHTS))
    confident = 0
    for frame in frames:
        blob = cv2.dnn.blobFromImage(frame, 1 / 255.0, (size, size), swapRB=True, crop=False)
        net.setInput(blob)
        expected = np.vstack(net.forward(net.getUnconnectedOutLayersNames()))
        (rows,) = session.run(["rows"], {"images": blob})
        assert rows.shape == expected.shape == (3 * 5 * (size // 32) ** 2, 85)
        np.testing.assert_allclose(rows, expected, rtol=0, atol=1e-4)
        confident += int((expected[:, 5:].max(axis=1) > 0.25).sum())
    assert confident >= 20  # the rows compared hold detections, not only the zeros below the floor


def test_both_runtimes_detect_the_same_objects_through_the_processor(frames: list[np.ndarray], cache: Path) -> None:
    opencv = YoloDetector(runtime="opencv", mode="paper")
    onnxruntime = YoloDetector(runtime="onnxruntime", mode="paper")
    assert (opencv.backend.runtime, onnxruntime.backend.runtime) == ("opencv", "onnxruntime")
    found = 0
    for frame in frames:
        opencv.photo_processing(frame.copy())
        onnxruntime.photo_processing(frame.copy())
        assert [d.label for d in onnxruntime.detections] == [d.label for d in opencv.detections]
        for ours, theirs in zip(onnxruntime.detections, opencv.detections, strict=True):
            np.testing.assert_allclose(ours.box, theirs.box, rtol=0, atol=0.01)  # pixels
            assert ours.score == pytest.approx(theirs.score, abs=1e-4)
        found += len(opencv.detections)
    assert found >= 15
    assert [p.suffix for p in cache.iterdir()] == [".onnx"]  # converted once, kept whole


def test_the_runtime_is_one_processor_argument(cache: Path) -> None:
    assert load_processor("yolo", {"runtime": "opencv"}).instance.backend.runtime == "opencv"
    assert load_processor("yolo", {"runtime": "onnxruntime"}).instance.backend.runtime == "onnxruntime"
    assert load_processor("yolo").instance.backend.runtime == "onnxruntime"  # the default where the extra is
    with pytest.raises(ProcessorLoadError, match="runtime must be one of onnxruntime, opencv, got 'tflite'"):
        load_processor("yolo", {"runtime": "tflite"})


def test_a_runtime_for_a_model_that_is_not_darknet_is_refused(tmp_path: Path) -> None:
    (tmp_path / "yolov8n.onnx").write_bytes(b"not read")
    with pytest.raises(ValueError, match="runtime='opencv' is for Darknet models; yolov8n.onnx"):
        load_backend(tmp_path / "yolov8n.onnx", DetectorConfig(), "opencv")


def _without(module: str, code: str) -> subprocess.CompletedProcess[str]:
    """``code`` in a fresh Python (this test's environment, its cache folder too) where ``import module`` fails as
    if it were not installed."""
    script = f"import sys\nsys.modules[{module!r}] = None\n{code}"
    return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60, cwd=REPO)


def _runtime(**args: str) -> str:
    """Code that loads ``yolo`` as the platform does, with ``args``, and prints its backend's runtime."""
    return f"from processors import load_processor\nprint(load_processor('yolo', {args!r}).instance.backend.runtime)"


def test_a_missing_onnxruntime_says_what_to_install(cache: Path) -> None:
    asked = _without("onnxruntime", _runtime(runtime="onnxruntime"))
    assert asked.returncode == 1
    assert f"runtime='onnxruntime' needs onnxruntime: {INSTALL}" in asked.stderr
    default = _without("onnxruntime", _runtime())
    assert default.stdout.strip() == "opencv", default.stderr  # without it the default is OpenCV DNN


def test_the_cached_graph_needs_no_onnx_and_a_first_conversion_does(cache: Path) -> None:
    before = _without("onnx", _runtime(runtime="onnxruntime"))
    assert before.returncode == 1 and f"needs onnx: {INSTALL}" in before.stderr
    assert Path(darknet_onnx_model(CFG, WEIGHTS, 320)).parent == cache
    after = _without("onnx", _runtime(runtime="onnxruntime"))
    assert after.stdout.strip() == "onnxruntime", after.stderr


def test_an_unwritable_cache_converts_in_memory(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "file").write_text("not a folder")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "file"))
    model = darknet_onnx_model(CFG, WEIGHTS, 320)
    assert isinstance(model, bytes)
    assert open_session(model, "the test").get_outputs()[0].shape == [1500, 85]


def test_the_converter_names_what_it_cannot_convert(tmp_path: Path) -> None:
    cfg = tmp_path / "odd.cfg"
    cfg.write_text(CFG.read_text() + "\n[sam]\nfrom=-2\n")
    with pytest.raises(ValueError, match=r"odd.cfg: layer 131 \[sam\] is not supported"):
        darknet_to_onnx(cfg, WEIGHTS, 320)
    cfg.write_text(CFG.read_text().replace("[route]\nlayers=-1,80", "[route]\nlayers=-1,80\ngroups=2", 1))
    with pytest.raises(ValueError, match=r"odd.cfg: layer \d+ \[route\] has groups, which the ONNX converter"):
        darknet_to_onnx(cfg, WEIGHTS, 320)
    short = tmp_path / "short.weights"
    short.write_bytes(WEIGHTS.read_bytes()[:500_000])
    with pytest.raises(ValueError, match="short.weights ends before the .cfg's layers do"):
        darknet_to_onnx(CFG, short, 320)
