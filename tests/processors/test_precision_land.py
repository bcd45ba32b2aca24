"""precision_land: the pad's pose from the sim: camera's marker, and a clear status (no target) on bad input."""

from __future__ import annotations

import logging
from typing import Any

import cv2
import numpy as np
import pytest

from processors import load_processor
from processors.frame_telemetry import FrameTelemetry
from processors.precision_land import PrecisionLand
from sources.ground import default_ground
from sources.sim_camera import SimCameraSource
from sources.sim_geometry import PinholeCamera, Pose, camera_centre, rotation_world_camera
from sources.sim_marker import GroundMarker
from sources.sim_render import SimRenderer
from uav_tui.errors import ProcessorLoadError
from uav_values.camera import CameraModel

CAMERA = PinholeCamera(640, 480, 62.0)
MODEL = SimCameraSource(camera=CAMERA).camera_model()
PAD = GroundMarker("4x4_50", 7, 0.5, n=2.0, e=-1.0)


@pytest.fixture(scope="module")
def renderer() -> SimRenderer:
    return SimRenderer(CAMERA, default_ground(0), noise_sigma=2.0, marker=PAD)


def run(processor: PrecisionLand, frame: np.ndarray, pose: Pose, camera: CameraModel | None = MODEL,
        seq: int = 1) -> np.ndarray:
    """One frame through the processor with the telemetry of ``pose``; returns the frame it drew on."""
    tm = FrameTelemetry(lambda image, extra: None)
    tm.camera_model = camera
    tm.begin(seq, seq * 33_000_000, 0, {"rel_alt_m": -pose.d, "roll_deg": pose.roll, "pitch_deg": pose.pitch,
                                         "yaw_deg": pose.yaw}, 0.1)
    processor.tmMgr = tm
    drawn = frame.copy()
    processor.photo_processing(drawn)
    return drawn


def truth_in_camera(pose: Pose, marker: GroundMarker = PAD) -> np.ndarray:
    """The marker's centre in the camera frame (metres), from the simulator's geometry."""
    centre = np.array([marker.n, marker.e, 0.0]) - camera_centre(pose)
    return rotation_world_camera(pose, CAMERA).T @ centre


ATTITUDES = {"level": (0.0, 0.0, 0.0), "tilted": (8.0, -10.0, 35.0), "tilted-back": (-12.0, 6.0, 200.0)}


@pytest.mark.parametrize("attitude", list(ATTITUDES.values()), ids=list(ATTITUDES))
@pytest.mark.parametrize("altitude", [5.0, 10.0], ids=["5m", "10m"])
@pytest.mark.parametrize("dictionary", ["4x4_50", "apriltag_36h11"])
def test_pose_within_two_percent_of_the_distance(altitude: float, attitude: tuple[float, float, float],
                                                  dictionary: str) -> None:
    pad = GroundMarker(dictionary, 7, 0.5, n=2.0, e=-1.0)
    renderer = SimRenderer(CAMERA, default_ground(0), noise_sigma=2.0, marker=pad)
    roll, pitch, yaw = attitude
    pose = Pose(n=0.5, e=0.3, d=-altitude, roll=roll, pitch=pitch, yaw=yaw)
    processor = PrecisionLand(dictionary, 7, 0.5)
    run(processor, renderer.render(pose, index=1), pose, seq=12)
    target = processor.getLandingTarget()
    assert target is not None, processor.status
    truth = truth_in_camera(pose, pad)
    error = np.linalg.norm(np.array(target.position_m) - truth) / np.linalg.norm(truth)
    assert error < 0.02, f"{error:.2%} at {np.linalg.norm(truth):.2f} m"
    assert target.frame_seq == 12 and target.distance_m == pytest.approx(np.linalg.norm(truth), rel=0.02)
    assert processor.status.startswith("marker 7 at ")


def test_overlay_outlines_the_pad_and_box_is_its_extent(renderer: SimRenderer) -> None:
    pose = Pose(d=-8.0)
    frame = renderer.render(pose, index=1)
    processor = PrecisionLand("4x4_50", 7, 0.5)
    drawn = run(processor, frame, pose)
    x, y, w, h = processor.box
    corners = [CAMERA.intrinsics @ (truth_in_camera(pose) + offset) for offset in ((-0.25, -0.25, 0), (0.25, 0.25, 0))]
    (u0, v0), (u1, v1) = ((c[:2] / c[2]) for c in corners)
    assert (x, y) == pytest.approx((min(u0, u1), min(v0, v1)), abs=2)
    assert (w, h) == pytest.approx((abs(u1 - u0), abs(v1 - v0)), abs=3)
    green = np.all(drawn == (0, 200, 0), axis=2)
    assert green[y - 2:y + h + 3, x - 2:x + w + 3].sum() > 2 * (w + h)  # the outline and the centre cross


def test_a_wrong_marker_size_is_caught_by_the_height_and_names_the_size_that_fits(renderer: SimRenderer) -> None:
    pose = Pose(d=-10.0)
    processor = PrecisionLand("4x4_50", 7, 1.0)  # the pad is 0.5 m: every distance comes out twice too long
    run(processor, renderer.render(pose, index=1), pose)
    assert processor.getLandingTarget() is None
    assert "size check" in processor.status and "0.50 m would fit" in processor.status
    unchecked = PrecisionLand("4x4_50", 7, 1.0, size_tolerance=None)  # a pad on a roof: the user turns it off
    run(unchecked, renderer.render(pose, index=1), pose)
    assert unchecked.getLandingTarget() is not None


def test_no_camera_model_says_so_and_gives_no_target(renderer: SimRenderer) -> None:
    pose = Pose(d=-10.0)
    processor = PrecisionLand("4x4_50", 7, 0.5)
    run(processor, renderer.render(pose, index=1), pose, camera=None)
    assert processor.getLandingTarget() is None and processor.box is not None
    assert processor.status.startswith("no camera model")


def test_two_markers_with_the_pad_id_give_no_target() -> None:
    vocabulary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    tile = cv2.copyMakeBorder(cv2.aruco.generateImageMarker(vocabulary, 7, 60), 15, 15, 15, 15,
                              cv2.BORDER_CONSTANT, value=255)
    frame = np.full((480, 640), 255, np.uint8)
    frame[100:190, 100:190] = tile
    frame[250:340, 400:490] = tile
    processor = PrecisionLand("4x4_50", 7, 0.5)
    run(processor, cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR), Pose(d=-10.0))
    assert [marker_id for marker_id, _ in processor.seen] == [7, 7]
    assert processor.getLandingTarget() is None and processor.status.startswith("2 markers with id 7")


@pytest.mark.parametrize(("left_px", "edge"), [(3, True), (8, False)], ids=["touching", "inside"])
def test_a_marker_touching_the_frame_edge_gives_no_target(left_px: int, edge: bool) -> None:
    """Found, but with a corner within EDGE_MARGIN_PX of the border: it may be cut off, its pose is not trusted."""
    vocabulary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    frame = np.full((480, 640), 255, np.uint8)
    frame[200:260, left_px:left_px + 60] = cv2.aruco.generateImageMarker(vocabulary, 7, 60)
    processor = PrecisionLand("4x4_50", 7, 0.5, size_tolerance=None)
    run(processor, cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR), Pose(d=-10.0))
    assert [marker_id for marker_id, _ in processor.seen] == [7]
    if edge:
        assert processor.getLandingTarget() is None
        assert processor.status == "marker 7 partly out of frame: no target"
    else:
        assert processor.getLandingTarget() is not None, processor.status


def test_a_pad_leaving_the_frame_is_reported_at_its_edge(renderer: SimRenderer) -> None:
    processor = PrecisionLand("4x4_50", 7, 0.5)
    inside = Pose(n=2.0, e=-1.0 + 5.4, d=-10.0)  # the pad 5.4 m west of the vehicle: 19 px from the left edge
    run(processor, renderer.render(inside, index=1), inside)
    assert processor.getLandingTarget() is not None, processor.status
    half_out = Pose(n=2.0, e=-1.0 + 6.0, d=-10.0)
    u = MODEL.ray_to_pixel(truth_in_camera(half_out))[0]
    assert abs(u) < 5  # the pad's centre is on the left border: half of it is out of the frame
    run(processor, renderer.render(half_out, index=1), half_out, seq=2)
    assert processor.getLandingTarget() is None
    assert processor.status == "marker 7 out of frame at the left edge (last seen there): no target"


def test_buttons_step_through_the_ids_in_view_and_pause(renderer: SimRenderer, caplog: Any) -> None:
    pose = Pose(d=-10.0)
    frame = renderer.render(pose, index=1)
    processor = PrecisionLand("4x4_50", 3, 0.5)
    run(processor, frame, pose)
    assert processor.getLandingTarget() is None and processor.status == "marker 3 not in view (in view: [7])"
    processor.customize_processing(1)  # F1: the next id in view
    assert processor.marker_id == 7
    run(processor, frame, pose)
    assert processor.getLandingTarget() is not None
    processor.customize_processing(3)  # F3: pause
    assert processor.getLandingTarget() is None
    processor.customize_processing(3)
    assert processor.getLandingTarget() is not None
    with caplog.at_level(logging.INFO, logger="processors.precision_land"):
        processor.customize_processing(4)  # F4: the pose in the log
    logged = caplog.records[-1].getMessage()
    assert logged.startswith("PrecisionLand: marker 7: ") and "deg right" in logged
    assert float(logged.split(": ")[2].split(" m")[0]) == pytest.approx(np.linalg.norm(truth_in_camera(pose)), rel=0.02)
    processor.customize_processing(1)  # no other id in view: id + 1
    assert processor.marker_id == 8
    processor.customize_processing(2)
    assert processor.marker_id == 7


def test_registered_by_name_with_its_arguments() -> None:
    loaded = load_processor("precision_land", {"dictionary": "DICT_APRILTAG_36h11", "marker_id": 4,
                                               "marker_size_m": 0.3})
    assert loaded.info.capabilities == {"customize_processing", "getLandingTarget"}
    assert (loaded.instance.dictionary, loaded.instance.marker_id) == ("DICT_APRILTAG_36H11", 4)
    with pytest.raises(ProcessorLoadError, match="apriltag_36h11"):
        load_processor("precision_land", {"dictionary": "apriltag"})


def test_the_status_is_logged_when_it_says_something_new_not_every_frame(renderer: SimRenderer, caplog: Any) -> None:
    processor = PrecisionLand("4x4_50", 7, 1.0)  # wrong size: the size check fails on every frame
    with caplog.at_level(logging.INFO, logger="processors.precision_land"):
        for seq, altitude in enumerate((10.0, 10.1, 10.2, 10.3), start=1):
            pose = Pose(d=-altitude)
            run(processor, renderer.render(pose, index=seq), pose, seq=seq)
        pose = Pose(d=-10.0)
        run(PrecisionLand("4x4_50", 7, 0.5), renderer.render(pose, index=1), pose)
    logged = [record.getMessage() for record in caplog.records]
    assert len(logged) == 2, logged
    assert logged[0].startswith("PrecisionLand: size check") and logged[1].startswith("PrecisionLand: marker 7 at ")
