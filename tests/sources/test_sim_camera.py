"""sim: the rendered image moves the way a pinhole camera on the vehicle would see it move."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from sources import create_source
from sources.ground import default_ground
from sources.pose import PoseAt
from sources.sim_camera import SimCameraSource
from sources.sim_geometry import PinholeCamera, Pose, project_ground_point
from sources.sim_render import SKY_BGR, SimRenderer, default_targets
from uav_tui.errors import SourceUriError

CAMERA = PinholeCamera(320, 240, hfov_deg=62.0)


@pytest.fixture(scope="module")
def renderer() -> SimRenderer:
    return SimRenderer(CAMERA, default_ground(0), noise_sigma=0.0)


def _shift(before: np.ndarray, after: np.ndarray) -> tuple[float, float]:
    """(dx, dy) pixels the content of ``after`` moved relative to ``before`` (phase correlation)."""
    grey = [cv2.cvtColor(image, cv2.COLOR_BGR2GRAY).astype(np.float32) for image in (before, after)]
    window = cv2.createHanningWindow(grey[0].shape[::-1], cv2.CV_32F)
    (dx, dy), _ = cv2.phaseCorrelate(grey[0], grey[1], window)
    return dx, dy


def test_hovering_frames_are_identical_up_to_noise() -> None:
    noisy = SimRenderer(CAMERA, default_ground(0), noise_sigma=2.0)
    hover = Pose(n=3.0, e=-2.0, d=-10.0, yaw=30.0)
    first, second = noisy.render(hover, index=0), noisy.render(hover, index=1)
    difference = np.abs(first.astype(np.int16) - second.astype(np.int16))
    assert 0 < difference.mean() < 4 and np.percentile(difference, 99) < 12
    moved = noisy.render(Pose(n=3.5, e=-2.0, d=-10.0, yaw=30.0), index=1)
    assert np.abs(first.astype(np.int16) - moved.astype(np.int16)).mean() > 3 * difference.mean()


@pytest.mark.parametrize("altitude", [10.0, 20.0])
def test_moving_one_metre_north_shifts_the_image_as_the_pinhole_model_predicts(renderer, altitude) -> None:
    here, north = Pose(d=-altitude), Pose(n=1.0, d=-altitude)
    dx, dy = _shift(renderer.render(here), renderer.render(north))
    expected = CAMERA.focal_px * 1.0 / altitude  # a downward camera: f * displacement / height
    assert expected == pytest.approx(project_ground_point(0, 0, north, CAMERA)[1] - CAMERA.height / 2)
    assert dy == pytest.approx(expected, abs=1.0)  # the ground slides towards the tail: down in the image
    assert abs(dx) < 1.0


def test_moving_east_with_yaw_90_shifts_the_image_down(renderer) -> None:
    # Nose pointing east: flying east is flying forward, so the ground slides down the image.
    dx, dy = _shift(renderer.render(Pose(yaw=90.0)), renderer.render(Pose(e=1.0, yaw=90.0)))
    assert dy == pytest.approx(CAMERA.focal_px / 10.0, abs=1.0) and abs(dx) < 1.0


def test_rolling_right_shifts_the_image_right(renderer) -> None:
    dx, dy = _shift(renderer.render(Pose()), renderer.render(Pose(roll=4.0)))
    # Right wing down tilts the camera to the left, so the ground it saw moves to the right of the image.
    assert dx == pytest.approx(CAMERA.focal_px * math.tan(math.radians(4.0)), abs=1.5)
    assert abs(dy) < 1.0


def test_pitching_nose_up_shifts_the_image_down(renderer) -> None:
    # Nose up swings a downward camera's view forward: like flying forward, the ground slides down the image.
    dx, dy = _shift(renderer.render(Pose()), renderer.render(Pose(pitch=4.0)))
    assert dy == pytest.approx(CAMERA.focal_px * math.tan(math.radians(4.0)), abs=1.5)
    assert abs(dx) < 1.0


def test_project_ground_point() -> None:
    assert project_ground_point(0, 0, Pose(), CAMERA) == pytest.approx((160, 120))
    assert project_ground_point(0, 1, Pose(), CAMERA)[0] == pytest.approx(160 + CAMERA.focal_px / 10)
    forward = PinholeCamera(320, 240, tilt_deg=0.0)
    assert project_ground_point(-5, 0, Pose(), forward) is None  # behind a forward-looking camera
    assert project_ground_point(10, 0, Pose(), forward) == pytest.approx((160, 120 + CAMERA.focal_px))


def test_a_landed_vehicle_still_renders_the_ground_close_up(renderer) -> None:
    landed = renderer.render(Pose(d=0.0))
    assert landed.std() > 5  # texture, not a degenerate fill
    assert project_ground_point(0, 0.1, Pose(d=0.0), CAMERA)[0] == pytest.approx(160 + CAMERA.focal_px * 0.1 / 0.2)


def test_forward_mount_sees_the_horizon_and_a_downward_one_does_not() -> None:
    forward = create_source("sim:?width=160&height=120&mount=forward&noise=0")
    down = create_source("sim:?width=160&height=120&noise=0")
    assert isinstance(forward, SimCameraSource) and forward.camera.tilt_deg == 0
    tilted = create_source("sim:?mount=forward&tilt=30&hfov=90")
    assert (tilted.camera.tilt_deg, tilted.camera.hfov_deg) == (30, 90)
    for source in (forward, down):
        assert source.open()
    try:
        sky = np.array(SKY_BGR, np.uint8)
        image = forward.buffer.wait_newer(0, 5).image
        assert np.all(image[:50] == sky) and not np.any(np.all(image[70:] == sky, axis=2))
        assert not np.any(np.all(down.buffer.wait_newer(0, 5).image == sky, axis=2))
    finally:
        forward.close()
        down.close()


def test_targets_appear_where_projected() -> None:
    targets = default_targets(1, speed_ms=2.0)
    renderer = SimRenderer(CAMERA, default_ground(0), targets)
    for t in (0.0, 3.0):
        n, e, _ = targets[0].position(t)
        pose = Pose(n=n + 1.0, e=e - 1.0, d=-15.0)
        u, v = project_ground_point(n, e, pose, CAMERA)
        b, g, r = renderer.render(pose, t)[round(v) - 3:round(v) + 4, round(u) - 3:round(u) + 4].mean(axis=(0, 1))
        assert r > 120 and r > 2 * g and r > 2 * b  # the red roof
    assert targets[0].position(3.0)[:2] != pytest.approx(targets[0].position(0.0)[:2])


def test_pose_provider_drives_the_view_and_failures_are_reported() -> None:
    poses = iter([None, PoseAt(Pose(n=2.0, e=1.0, d=-8.0, roll=1.0, pitch=0.0, yaw=45.0), 0.012)])
    asked: list[int] = []

    def provider(t_mono_ns: int) -> PoseAt | None:
        asked.append(t_mono_ns)
        try:
            return next(poses)
        except StopIteration:
            raise ConnectionError("telemetry gone") from None

    source = create_source("sim:?width=64&height=48&fps=100", pose_provider=provider)
    assert source.open()
    try:
        first = source.buffer.wait_newer(0, 5)
        second = source.buffer.wait_newer(first.seq, 5)
        assert second is not None
        assert source.buffer.wait_newer(second.seq + 1, 5) is not None  # keeps delivering after the failure
        props = source.get_properties()
        assert props["pose"] == {"n": 2.0, "e": 1.0, "d": -8.0, "roll": 1.0, "pitch": 0.0, "yaw": 45.0}
        assert props["pose_source"] == "vehicle telemetry" and "telemetry gone" in props["last_error"]
        assert props["pose_extrapolated_ms"] == 12.0
        # The pose is the one at the frame's capture time (asked for each frame; the newest frame may be a later one).
        assert second.t_mono_ns in asked and asked == sorted(asked)
    finally:
        source.close()


def test_no_pose_renders_the_default_hover_and_targets_are_reported() -> None:
    source = create_source("sim:?width=160&height=120&targets=2&noise=0")
    assert source.open()
    try:
        frame = source.buffer.wait_newer(0, 5)
        assert frame is not None
        props = source.get_properties()
        assert props["pose_source"].startswith("default hover at 10 m")
        assert len(props["targets"]) == 2
        first = props["targets"][0]
        assert math.hypot(first["n"], first["e"]) == pytest.approx(6.0)  # the first ring
        corners = np.array(first["corners"])  # a 4 x 2 m car around its position
        assert corners.shape == (4, 2) and corners.mean(axis=0) == pytest.approx([first["n"], first["e"]], abs=0.01)
        sides = np.linalg.norm(corners - np.roll(corners, 1, axis=0), axis=1)
        assert sorted(sides) == pytest.approx([2, 2, 4, 4], abs=0.02)
    finally:
        source.close()


@pytest.mark.parametrize("uri", ["sim:?mount=sideways", "sim:?hfov=200", "sim:?zoom=2"], ids=["mount", "hfov", "typo"])
def test_bad_options(uri: str) -> None:
    with pytest.raises(SourceUriError):
        create_source(uri)


def test_a_marker_from_the_uri_is_drawn_where_configured_and_reported() -> None:
    source = create_source("sim:?width=320&height=240&noise=0&marker=7&marker_dict=apriltag_36h11&marker_size=1.5"
                           "&marker_at=2,-1")
    assert source.get_properties()["marker"] == {"dictionary": "apriltag_36h11", "id": 7, "size_m": 1.5,
                                                 "n": 2.0, "e": -1.0}
    renderer = SimRenderer(source.camera, default_ground(0), marker=source.marker)
    image = renderer.render(Pose(d=-10.0))
    u, v = project_ground_point(2.0, -1.0, Pose(d=-10.0), source.camera)
    detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11))
    corners, ids, _ = detector.detectMarkers(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY))
    assert ids is not None and ids.ravel().tolist() == [7]
    assert corners[0].reshape(4, 2).mean(axis=0) == pytest.approx((u, v), abs=0.5)
    side = np.linalg.norm(corners[0][0, 1] - corners[0][0, 0])
    assert side == pytest.approx(1.5 * source.camera.focal_px / 10.0, rel=0.03)


@pytest.mark.parametrize(("query", "message"), [
    ("marker_size=0.5", "need marker=ID"),
    ("marker=7&marker_dict=5x5_9", "not one of OpenCV's"),
    ("marker=70&marker_dict=4x4_50", "ids 0..49"),
    ("marker=1&marker_at=north", "N,E in metres"),
], ids=["size-without-id", "dictionary", "id", "position"])
def test_a_wrong_marker_in_the_uri_says_what_is_expected(query: str, message: str) -> None:
    with pytest.raises(SourceUriError, match=message):
        create_source(f"sim:?{query}")
