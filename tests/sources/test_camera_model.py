"""The camera model: pixel <-> ray, the sim: camera's exact model, calibration files, the [camera] configuration,
and calibration on a chessboard rendered with the sim: camera's intrinsics."""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from sources import create_source
from sources.calibration import calibrate, load_model, read_calibration, write_calibration
from sources.sim_geometry import Pose, project_ground_point, rotation_world_body
from tests.sources.chessboard import CHARUCO, CHESSBOARD, render_views
from uav_tui.cli import main
from uav_tui.config import add_config_flags, load_config, overrides_from_args
from uav_tui.errors import ConfigError
from uav_values.camera import CameraModel, CameraModelError, Mount

BARREL = (-0.28, 0.09, 0.0008, -0.0005, -0.01)
"""A wide-angle lens's distortion (k1, k2, p1, p2, k3)."""

# An OpenCV calibration file as OpenCV's calibration sample writes it (cv2.FileStorage YAML).
SAMPLE_YAML = """%YAML:1.0
---
calibration_time: "Thu 26 Nov 2026 10:00:00 UTC"
nr_of_frames: 25
image_width: 640
image_height: 480
board_width: 9
board_height: 6
square_size: 2.5000000000000001e-02
flags: 0
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 5.0512e+02, 0., 3.1875e+02, 0., 5.0488e+02, 2.4210e+02, 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 5
   cols: 1
   dt: d
   data: [ -2.8e-01, 9.0e-02, 8.0e-04, -5.0e-04, -1.0e-02 ]
avg_reprojection_error: 2.1e-01
"""


def sim_model(uri: str = "sim:") -> CameraModel:
    return create_source(uri).camera_model()


@pytest.mark.parametrize("distortion", [(), BARREL], ids=["pinhole", "barrel"])
def test_pixel_to_ray_to_pixel_returns_the_pixel(distortion: tuple[float, ...]) -> None:
    model = CameraModel(640, 480, 505.1, 504.9, 318.7, 242.1, distortion)
    pixels = np.array([(u, v) for u in (0.0, 13.5, 320.0, 500.25, 639.0) for v in (0.0, 97.0, 240.0, 479.0)])
    rays = model.pixels_to_rays(pixels)
    assert np.allclose(np.linalg.norm(rays, axis=1), 1.0)
    assert np.allclose(model.rays_to_pixels(rays), pixels, atol=1e-6)
    for (u, v), ray in zip(pixels, rays, strict=True):
        assert np.allclose(model.pixel_to_ray(u, v), ray, atol=1e-9)
        assert np.allclose(model.ray_to_pixel(ray), (u, v), atol=1e-6)
    if distortion:  # the corner's ray is not the pinhole's: distortion is really removed
        assert not np.allclose(rays[0], CameraModel(640, 480, 505.1, 504.9, 318.7, 242.1).pixel_to_ray(0, 0))
    assert model.ray_to_pixel(np.array([0.0, 0.0, -1.0])) is None  # behind the camera
    assert model.angles(model.cx, model.cy) == pytest.approx((0.0, 0.0))


@pytest.mark.parametrize(("uri", "point"), [("sim:", (3.0, 1.0)), ("sim:?mount=forward&tilt=30&hfov=80", (25.0, 4.0))],
                         ids=["down", "tilted"])
def test_the_sim_camera_states_the_model_it_renders_with(uri: str, point: tuple[float, float]) -> None:
    """A ground point drawn at a pixel by the renderer's homography is found again from that pixel's ray."""
    model = sim_model(uri)
    assert model.origin == "sim: renderer (exact)" and model.distortion == ()
    pose = Pose(n=1.0, e=-2.0, d=-10.0, roll=4.0, pitch=-3.0, yaw=30.0)
    pixel = project_ground_point(*point, pose, create_source(uri).camera)
    assert pixel is not None and 0 <= pixel[0] < model.width and 0 <= pixel[1] < model.height
    ray = rotation_world_body(pose.roll, pose.pitch, pose.yaw) @ model.ray_in_body(model.pixel_to_ray(*pixel))
    ground = np.array([pose.n, pose.e, pose.d]) + ray * (-pose.d / ray[2])
    assert ground[:2] == pytest.approx(point, abs=1e-9)


def test_the_sim_camera_model_follows_its_uri() -> None:
    model = sim_model("sim:?width=320&height=240&hfov=70&mount=forward")
    assert (model.width, model.height, model.mount.tilt_deg) == (320, 240, 0.0)
    assert model.fx == model.fy == pytest.approx(160 / math.tan(math.radians(35)))
    assert model.hfov_deg == pytest.approx(70.0)
    assert model.ray_in_body(np.array([0.0, 0.0, 1.0])) == pytest.approx([1.0, 0.0, 0.0])  # looks ahead
    assert sim_model().ray_in_body(np.array([0.0, -1.0, 0.0])) == pytest.approx([1.0, 0.0, 0.0])  # image top: nose
    assert create_source("synthetic:").camera_model() is None  # cannot know: the configured one, or none


@pytest.mark.parametrize("charuco", [False, True], ids=["chessboard", "charuco"])
def test_calibration_on_a_rendered_board_recovers_the_sim_cameras_intrinsics(charuco: bool) -> None:
    truth = sim_model()
    board = CHARUCO if charuco else CHESSBOARD
    views = [board.find(image) for image in render_views(truth, 12, charuco=charuco)]
    assert all(view is not None for view in views)
    found = calibrate(views, (truth.width, truth.height)).model()
    for name in ("fx", "fy", "cx", "cy"):
        assert getattr(found, name) == pytest.approx(getattr(truth, name), rel=0.01), name
    assert found.rms_px < 0.5


@pytest.mark.parametrize("suffix", [".yaml", ".json", ".xml"])
def test_a_written_calibration_file_reads_back(tmp_path: Path, suffix: str) -> None:
    views = [CHESSBOARD.find(image) for image in render_views(sim_model(), 5)]
    calibration = calibrate(views, (640, 480))
    path = tmp_path / f"camera{suffix}"
    write_calibration(path, calibration, CHESSBOARD)
    model = load_model(path, Mount.parse("forward", "0.1,0,0.05"))
    assert (model.width, model.height, model.rms_px) == (640, 480, pytest.approx(calibration.rms_px))
    assert np.allclose(model.matrix, calibration.matrix) and np.allclose(model.distortion, calibration.distortion)
    assert model.mount == Mount(0.0, (0.1, 0.0, 0.05)) and str(path) in model.origin


def test_opencv_samples_calibration_file_loads(tmp_path: Path) -> None:
    path = tmp_path / "out_camera_data.yml"
    path.write_text(SAMPLE_YAML)
    model = load_model(path)
    assert (model.fx, model.fy, model.cx, model.cy) == (505.12, 504.88, 318.75, 242.10)
    assert model.distortion == pytest.approx(BARREL) and model.rms_px == pytest.approx(0.21)
    assert "RMS 0.21 px" in model.describe()


@pytest.mark.parametrize(("text", "problem"), [
    ("camera_matrix: [1, 2\n  : : garbage {{", "not an OpenCV calibration file"),
    ("%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n", "camera_matrix, distortion_coefficients missing"),
    (SAMPLE_YAML.replace("rows: 3\n   cols: 3", "rows: 1\n   cols: 9"), "camera_matrix must be 3x3"),
    (SAMPLE_YAML.replace("image_width: 640", "image_width: 640.5"), "whole numbers of pixels"),
    (SAMPLE_YAML.replace("5.0512e+02", "-5.0512e+02"), "must be > 0"),
], ids=["garbage", "missing", "matrix-shape", "width", "negative-focal"])
def test_a_calibration_file_that_does_not_parse_says_what_to_do(tmp_path: Path, text: str, problem: str) -> None:
    path = tmp_path / "camera.yaml"
    path.write_text(text)
    with pytest.raises(CameraModelError, match=problem) as raised:
        read_calibration(path)
    assert str(path) in str(raised.value) and "uav-tui calibrate --source URI" in str(raised.value)


@pytest.mark.parametrize(("edit", "problem"), [
    (("5.0512e+02, 0., 3.1875e+02, 0., 5.0488e+02", "1e-06, 0., 3.1875e+02, 0., 1e-06"), "field of view of 180 x 180"),
    (("5.0512e+02, 0., 3.1875e+02, 0., 5.0488e+02", "1e12, 0., 3.1875e+02, 0., 1e12"), "field of view of 3.67e-08"),
    (("3.1875e+02", "-1e6"), r"principal point \(-1e\+06, 242.1\) is outside the 640x480 image"),
    (("-1.0e-02 ]", "1e9 ]"), "scales the radius at the image's corner by"),
    (("-2.8e-01, 9.0e-02", "-6.0e-01, 0."), "not one-to-one over the image: its radial function turns back"),
    (("0., 5.0488e+02", "0., 1.5e+03"), "fy / fx = 2.97 is not a camera's"),
], ids=["fx-1e-6", "fx-1e12", "cx-outside", "k3-1e9", "folding-barrel", "aspect"])
def test_a_calibration_file_that_is_no_camera_is_refused(tmp_path: Path, edit: tuple[str, str], problem: str) -> None:
    """An edited file with finite, positive numbers that describe no lens says what is wrong and how to fix it."""
    path = tmp_path / "camera.yaml"
    assert edit[0] in SAMPLE_YAML
    path.write_text(SAMPLE_YAML.replace(*edit))
    with pytest.raises(CameraModelError, match=problem) as raised:
        load_model(path)
    assert str(path) in str(raised.value) and "uav-tui calibrate --source URI" in str(raised.value)


def test_a_missing_calibration_file_says_how_to_make_one(tmp_path: Path) -> None:
    with pytest.raises(CameraModelError, match="does not exist; make one with: uav-tui calibrate"):
        read_calibration(tmp_path / "nope.yaml")


def test_a_calibration_for_another_resolution_says_what_to_do(tmp_path: Path) -> None:
    path = tmp_path / "camera.yaml"
    path.write_text(SAMPLE_YAML)
    model = load_model(path)
    model.check_size(640, 480)
    with pytest.raises(CameraModelError, match=r"for 640x480 frames but the camera gives 1280x720 .*calibrate at this "
                       r"size \(uav-tui calibrate --source URI\) or set the camera's width/height to match"):
        model.check_size(1280, 720)


def cli(*argv: str) -> dict:
    parser = argparse.ArgumentParser()
    add_config_flags(parser)
    return overrides_from_args(parser.parse_args(list(argv)))


def test_the_camera_configuration_forms_parse(tmp_path: Path) -> None:
    calibration = tmp_path / "camera.yaml"
    calibration.write_text(SAMPLE_YAML)
    path = tmp_path / "uav.toml"
    path.write_text(f'[camera]\ncamera_calibration = "{calibration}"\ncamera_mount = "forward"\n'
                    'camera_offset = "0.12, 0, 0.04"\n')
    model = load_config(path).camera.model(640, 480)
    assert model == load_model(calibration, Mount(0.0, (0.12, 0.0, 0.04)))
    hfov = load_config(None, cli("--camera-hfov", "90", "--camera-mount", "45", "--camera-offset", "0,0,0.1")
                       ).camera.model(160, 120)
    assert (hfov.fx, hfov.cx, hfov.mount.tilt_deg, hfov.origin) == (pytest.approx(80.0), 80.0, 45.0,
                                                                     "camera_hfov 90 deg (no distortion)")
    assert load_config(None).camera.model(640, 480) is None  # nothing configured: no camera model


@pytest.mark.parametrize(("argv", "problem"), [
    (("--camera-mount", "sideways"), "--camera-mount: mount 'sideways' must be down, forward, gimbal or a tilt"),
    (("--camera-offset", "0.1,0"), "--camera-offset: offset '0.1,0' must be F,R,D in metres"),
    (("--camera-hfov", "200"), "--camera-hfov = 200.0 is out of range"),
    (("--camera-calibration", "/nonexistent/camera.yaml"), "does not exist; make one with: uav-tui calibrate"),
    (("--camera-mount", "forward"), "camera_mount places the configured camera model, but there is none: set "
                                    "camera_calibration or camera_hfov too"),
])
def test_bad_camera_settings_name_the_key_and_what_to_do(argv: tuple[str, ...], problem: str) -> None:
    with pytest.raises(ConfigError, match=problem):
        load_config(None, cli(*argv))



def _board_video(path: Path, views: list[np.ndarray]) -> Path:
    """The views as a lossless video (FFV1), each shown for 3 frames."""
    height, width = views[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"FFV1"), 10, (width, height))
    assert writer.isOpened()
    for image in views:
        for _ in range(3):
            writer.write(image)
    writer.release()
    return path


def test_uav_tui_calibrate_writes_the_file_with_its_rms(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    truth = sim_model()
    video = _board_video(tmp_path / "board.avi", render_views(truth, 12, seed=1))
    out = tmp_path / "camera.yaml"
    assert main(["calibrate", "--source", f"file:{video}?realtime=0", "--views", "10", "--interval", "0",
                 "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "looking for a 9x6 chessboard" in printed and "view 10/10: board found" in printed
    assert f"wrote {out}: use it with --camera-calibration {out}" in printed
    model = load_model(out)
    assert f"RMS reprojection error {model.rms_px:.3f} px over 10 views of 640x480" in printed
    for name in ("fx", "fy", "cx", "cy"):
        assert getattr(model, name) == pytest.approx(getattr(truth, name), rel=0.01), name


def test_uav_tui_calibrate_refuses_a_board_that_was_never_tilted(tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture[str]) -> None:
    """Moved over the whole image but always square to the camera: OpenCV would fit a focal length of thousands of
    pixels with an RMS under 0.2 px; nothing is written and the operator is told to tilt the board."""
    video = _board_video(tmp_path / "board.avi", render_views(sim_model(), 12, seed=1, tilted=False))
    out = tmp_path / "camera.yaml"
    assert main(["calibrate", "--source", f"file:{video}?realtime=0", "--views", "10", "--interval", "0",
                 "--out", str(out)]) == 1
    captured = capsys.readouterr()
    assert "view 10/10: board found" in captured.out and not out.exists()
    assert "nothing written: the board was not tilted in enough views (0 of 10 tilted, 3 needed)" in captured.err
    assert "tilt it towards and away from the camera" in captured.err


def test_calibration_refuses_views_that_leave_the_image_edges_unseen() -> None:
    """Tilted views, but all far away in the middle of the image: the distortion there is unknown."""
    views = [CHESSBOARD.find(image) for image in render_views(sim_model(), 10, distance_m=(0.8, 0.9))]
    assert all(view is not None for view in views)
    with pytest.raises(CameraModelError, match=r"covered only 4 of the image's 16 cells \(4x4\), 8 needed: .* near "
                       "the corners and edges"):
        calibrate(views, (640, 480))


def test_calibration_refuses_views_that_leave_the_intrinsics_uncertain() -> None:
    """Tilted, spread views, but few and with corners found to 1 px only: OpenCV reports fx to +-3 %."""
    rng = np.random.default_rng(0)
    views = [(objects, (points + rng.normal(0.0, 1.0, points.shape)).astype(np.float32))
             for objects, points in (CHESSBOARD.find(image) for image in render_views(sim_model(), 5))]
    with pytest.raises(CameraModelError, match=r"nothing written: the views leave the intrinsics uncertain \(fx "
                       r"\+-3\.\d%, fy \+-3\.\d%.* at most 2% is taken: blurred corners, or too few views\)"):
        calibrate(views, (640, 480))


def test_uav_tui_calibrate_says_what_to_do_when_it_sees_no_board(tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "camera.yaml"
    assert main(["calibrate", "--source", "synthetic:?width=160&height=120", "--views", "3", "--timeout", "6",
                 "--out", str(out)]) == 1
    printed = capsys.readouterr().out
    assert "no board found for 5 s: show the whole board, flat, well lit" in printed
    assert "--board is its inner corners: 9x6 for a board of 10x7 squares" in printed
    assert "gave up after 6 s with 0 of 3 views: nothing written" in printed and not out.exists()


def test_uav_tui_calibrate_refuses_a_bad_board(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["calibrate", "--source", "synthetic:", "--board", "9by6"]) == 2
    assert "--board '9by6' must be COLSxROWS inner corners" in capsys.readouterr().err


def test_a_model_round_trips_through_run_json_and_a_damaged_one_is_none(tmp_path: Path) -> None:
    model = CameraModel(640, 480, 505.1, 504.9, 318.7, 242.1, BARREL, Mount(30.0, (0.1, 0.0, 0.05)), "file x", 0.2)
    (tmp_path / "run.json").write_text(json.dumps({"camera": model.to_dict()}))
    recorded = create_source(f"run:{tmp_path}").camera_model()
    assert recorded == dataclasses.replace(model, origin=f"recorded in {tmp_path.name}: file x")
    (tmp_path / "run.json").write_text(json.dumps({"camera": {**model.to_dict(), "fx": "wide"}}))
    assert create_source(f"run:{tmp_path}").camera_model() is None
    (tmp_path / "run.json").write_text(json.dumps({"camera": None}))  # recorded without a model
    assert create_source(f"run:{tmp_path}").camera_model() is None


@pytest.mark.parametrize("offset", [[0.1, 0.0], [0.1, 0.0, 0.05, 1.0]])
def test_a_recorded_mount_offset_of_other_than_three_values_is_refused(offset: list[float]) -> None:
    data = {**CameraModel(640, 480, 505.1, 504.9, 318.7, 242.1).to_dict(), "offset_m": offset}
    with pytest.raises(CameraModelError, match="a value is missing or wrong"):
        CameraModel.from_dict(data)


def test_uav_tui_calibrate_with_a_charuco_board(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A board printed by --write-board, seen in part or whole, calibrates the camera as well."""
    printed_board = tmp_path / "board.png"
    assert main(["calibrate", "--charuco", "--write-board", str(printed_board)]) == 0
    assert cv2.imread(str(printed_board), cv2.IMREAD_GRAYSCALE).shape == (500, 700)
    truth = sim_model()
    video = _board_video(tmp_path / "board.avi", render_views(truth, 12, seed=3, charuco=True))
    out = tmp_path / "camera.json"
    assert main(["calibrate", "--charuco", "--source", f"file:{video}?realtime=0", "--views", "10", "--interval", "0",
                 "--out", str(out)]) == 0
    assert "looking for a 7x5 ChArUco board (DICT_4X4_50)" in capsys.readouterr().out
    model = load_model(out)
    for name in ("fx", "fy", "cx", "cy"):
        assert getattr(model, name) == pytest.approx(getattr(truth, name), rel=0.01), name
    assert cv2.FileStorage(str(out), cv2.FILE_STORAGE_READ).getNode("board_type").string() == "charuco"


def test_uav_tui_calibrate_refuses_an_unknown_dictionary(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["calibrate", "--charuco", "--dictionary", "DICT_9X9_1"]) == 2
    assert "unknown ArUco dictionary 'DICT_9X9_1'; OpenCV's are DICT_4X4_100" in capsys.readouterr().err
