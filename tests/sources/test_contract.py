"""The CameraSource contract, run over every built-in implementation."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import cv2
import pytest

from sources import CameraSource, create_source
from sources.pose import PoseAt
from sources.sim_geometry import Pose
from sources.uri import SourceUri
from sources.usb import UsbSource

COMMON_KEYS = {"kind", "device", "width", "height", "fps", "frames_captured", "frames_dropped", "last_error",
               "stalled_since"}

SourceFactory = Callable[[pytest.FixtureRequest], CameraSource]


def _synthetic(request: pytest.FixtureRequest) -> CameraSource:
    return create_source("synthetic:?width=160&height=120&fps=60")


def _file(request: pytest.FixtureRequest) -> CameraSource:
    clip = request.getfixturevalue("video_file")(fps=60)
    return create_source(f"file:{clip}")


def _usb_reading_a_file(request: pytest.FixtureRequest) -> CameraSource:
    clip = request.getfixturevalue("video_file")(fps=60)
    return UsbSource.from_uri(SourceUri.parse(f"usb:{clip}?width=640&height=480"),
                              capture_factory=lambda device: cv2.VideoCapture(device, cv2.CAP_FFMPEG))


def _picam_standin(request: pytest.FixtureRequest) -> CameraSource:
    request.getfixturevalue("picamera2_standin")
    return create_source("picam:0?width=320&height=240&fps=60")


def _sim(request: pytest.FixtureRequest) -> CameraSource:
    return create_source("sim:?width=160&height=120&fps=60",
                         pose_provider=lambda t_mono_ns: PoseAt(Pose(n=1.0, e=2.0, d=-12.0), 0.0))


def _rtsp(request: pytest.FixtureRequest) -> CameraSource:
    return create_source(request.getfixturevalue("rtsp_server").url)


def _http_mjpeg(request: pytest.FixtureRequest) -> CameraSource:
    return create_source(request.getfixturevalue("mjpeg_server").url)


IMPLEMENTATIONS: dict[str, SourceFactory] = {
    "synthetic": _synthetic,
    "file": _file,
    "usb-reading-a-file": _usb_reading_a_file,
    "picam-standin": _picam_standin,
    "sim": _sim,
    "rtsp": _rtsp,
    "http-mjpeg": _http_mjpeg,
}


@pytest.fixture(params=list(IMPLEMENTATIONS), ids=list(IMPLEMENTATIONS))
def source(request: pytest.FixtureRequest) -> Iterator[CameraSource]:
    camera = IMPLEMENTATIONS[request.param](request)
    yield camera
    camera.close()


def test_opens_and_delivers_bgr_frames_with_rising_seq(source: CameraSource) -> None:
    assert source.open(), source.get_properties()["last_error"]
    width, height = source.get_frame_size()
    seqs = []
    seq = 0
    for _ in range(3):
        frame = source.buffer.wait_newer(seq, timeout=10)
        assert frame is not None, f"no frame: {source.get_properties()}"
        assert frame.image.dtype == "uint8" and frame.image.shape == (height, width, 3)
        seqs.append(seq := frame.seq)
    assert seqs == sorted(seqs) and len(set(seqs)) == 3
    ok, image = source.read()
    assert ok and image is not None and image.shape == (height, width, 3)


def test_reports_the_common_properties(source: CameraSource) -> None:
    assert source.open()
    assert source.buffer.wait_newer(0, timeout=10) is not None
    props = source.get_properties()
    assert props.keys() >= COMMON_KEYS
    assert (props["width"], props["height"]) == source.get_frame_size()
    assert props["fps"] > 0 and props["frames_captured"] >= 1
    assert props["last_error"] is None and props["stalled_since"] is None


def test_close_twice_is_safe_and_stops_capturing(source: CameraSource) -> None:
    assert source.open()
    assert source.buffer.wait_newer(0, timeout=10) is not None
    source.close()
    source.close()
    captured = source.get_properties()["frames_captured"]
    assert source.buffer.wait_newer(captured, timeout=0.3) is None
    assert source.get_properties()["running"] is False
