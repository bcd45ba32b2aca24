"""The operator's lock on a track (issue 50): its states, the vector it makes, taking the locked object back under a
new number by its look, and its releases. Flown on the built-in vehicle: tests/flight/test_lock_flight.py."""

from __future__ import annotations

import dataclasses
import math

import cv2
import msgspec
import numpy as np
import pytest
from skimage import data

from processors.gimbal_steering import GimbalSteering
from processors.outputs import FrameOutputs
from processors.steering import Steering
from processors.yolo_detector import YoloDetector
from sources.buffer import Frame
from sources.ground import default_ground
from sources.sim_geometry import PinholeCamera, Pose, project_ground_point
from sources.sim_render import SimRenderer, default_targets
from uav_tui.errors import CommandError
from uav_tui.events import EventLog
from uav_tui.flight.appearance import likeness, look
from uav_tui.flight.track_lock import NEAREST, SAME_LOOK, LockState, TrackLock
from uav_tui.flight.track_overlay import LOCK_COLOUR, NUMBER_COLOUR, draw_tracks
from uav_tui.hosting.frame_call import call_frame
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.tracks import DetectionTracks
from uav_tui.hosting.wire import FrameOutcome
from uav_values.camera import CameraModel, Mount
from uav_values.detections import Detected
from uav_values.gimbal import GimbalPointing

RED, BLUE, DIM_RED = (40, 40, 200), (200, 60, 30), (30, 30, 150)
"""BGR cars: a red one, a blue one, the red one in a shadow."""
FPS = 10


def frame(n: int, cars: dict[int, tuple[tuple[int, int, int, int], tuple[int, int, int]]],
          vector: object = (0.3, 0.0, 1.0)) -> ProcessedFrame:
    """Frame ``n`` (at 10 fps) of a grey 320 x 240 picture with ``cars`` (track id -> box, colour) on it, each
    detected as a ``car``; its processor's own vector ``vector``."""
    image = np.full((240, 320, 3), 110, np.uint8)
    for (x, y, w, h), colour in cars.values():
        image[y:y + h, x:x + w] = colour
        image[y + h // 2, x:x + w] = 255  # a white stripe across the roof
    found = tuple(Detected(box, "car", 0.9, track_id=i) for i, (box, _) in cars.items())
    return ProcessedFrame(Frame(image, n, round(n * 1e9 / FPS), 0),
                          FrameOutcome(0, 0, vector=vector, detections=found))


def locked(lost_after_s: float = 1.0) -> tuple[TrackLock, EventLog]:
    events = EventLog()
    lock = TrackLock(events, lambda: lost_after_s)
    lock.steer(frame(0, {3: ((200, 60, 40, 30), RED), 5: ((40, 150, 30, 40), BLUE)}))
    assert lock.lock(3, None) == "locked on track #3 (car)"
    return lock, events


def test_the_locked_track_makes_the_vector_and_the_box_instead_of_the_processor() -> None:
    lock, _ = locked()
    seen = [lock.steer(frame(n, {3: ((200 + min(n, 11), 60, 40, 30), RED), 5: ((40, 150, 30, 40), BLUE)}))
            for n in range(1, 25)]
    last = seen[-1]
    assert last.outcome.box == (211, 60, 40, 30) and lock.state is LockState.LOCKED
    # The trackers' steering towards the box (right of and above the centre of a down camera), eased in.
    vx, vy, t = Steering("down", 2.0).vector(last.outcome.box, (320, 240))
    assert last.outcome.vector == pytest.approx((vx, vy, t)) and vx > 0 and vy > 0
    eased = [s.outcome.vector for s in seen]
    assert eased[0][:2] == (0.0, 0.0) and 0 < eased[1][1] < eased[3][1] < vy  # eased in
    assert str(lock.status()) == "locked on #3 car"


def test_a_detector_missing_a_frame_neither_says_the_lock_lost_nor_eases_in_again() -> None:
    lock, events = locked()
    vectors = []
    for n in range(1, 13):  # the car missed on every third frame
        result = lock.steer(frame(n, {} if n % 3 == 0 else {3: ((250, 20, 40, 30), RED)}))
        vectors.append(result.outcome.vector)
    assert [v is None for v in vectors] == [n % 3 == 0 for n in range(1, 13)]
    speeds = [math.hypot(v[0], v[1]) for v in vectors if v is not None]
    assert speeds == sorted(speeds) and speeds[-1] > 0.6  # eased in all along: 0.1 m/s a frame at 10 fps
    assert not any("lost" in e.message for e in events.recent)
    for n in range(13, 19):
        lock.steer(frame(n, {}))
    assert [e.message for e in events.recent if "lost" in e.message] == ["lock: #3 car lost"]  # once, after 0.5 s


def test_a_forward_camera_steers_to_keep_the_lock_time_size() -> None:
    lock = TrackLock(EventLog(), lambda: 0.0)
    lock.steer(frame(0, {1: ((140, 105, 40, 30), RED)}))
    lock.lock(1, CameraModel.from_hfov(320, 240, 60.0, Mount(tilt_deg=20.0)))
    for n in range(1, 30):  # it moves away: smaller
        result = lock.steer(frame(n, {1: ((150, 110, 20, 15), RED)}))
    assert result.outcome.vector[0] == pytest.approx(1.0)  # forward at max speed (2 x half the height lost)


def test_a_camera_on_the_gimbal_turns_the_gimbal_towards_the_lock_instead_of_flying() -> None:
    asked: list[int] = []

    def gimbal_pitch(t_ns: int) -> float:
        asked.append(t_ns)
        return -30.0

    lock = TrackLock(EventLog(), lambda: 0.0, gimbal_pitch)
    camera = CameraModel.from_hfov(320, 240, 60.0, Mount(0.0, gimbal=True))
    lock.steer(frame(0, {1: ((140, 105, 40, 30), RED)}))
    lock.lock(1, camera)
    given = frame(1, {1: ((240, 45, 40, 30), RED)})  # right of and above the centre
    pointed = msgspec.structs.replace(given.outcome, outputs=FrameOutputs(gimbal=GimbalPointing.rates(0, -9)))
    result = lock.steer(dataclasses.replace(given, outcome=pointed))
    assert result.outcome.vector is None and lock.vector is None and result.outcome.box == (240, 45, 40, 30)
    expected = GimbalSteering().rates((240, 45, 40, 30), (320, 240), camera, -30.0)
    assert result.outcome.outputs.gimbal == expected and expected.pitch > 0 and expected.yaw > 0  # up and right
    assert asked == [result.frame.t_mono_ns]  # the gimbal's pitch at the frame's capture
    hidden = lock.steer(frame(2, {}))
    assert hidden.outcome.outputs.gimbal is None and hidden.outcome.vector is None  # the relay stops the gimbal


def test_only_a_track_on_the_newest_frame_can_be_locked() -> None:
    lock, _ = locked()
    with pytest.raises(CommandError, match=r"lock 9: no track 9 on the newest frame \(its tracks: #3, #5\)"):
        lock.lock(9, None)
    lock.steer(frame(1, {}))
    with pytest.raises(CommandError, match="it has no tracks"):
        TrackLock(EventLog(), lambda: 0.0).lock(0, None)


def test_a_lost_lock_takes_back_a_new_track_that_looks_alike_not_another_car() -> None:
    lock, events = locked()
    for n in range(1, 4):
        lock.steer(frame(n, {3: ((200, 60, 40, 30), RED), 5: ((40, 150, 30, 40), BLUE)}))
    hidden = lock.steer(frame(4, {5: ((40, 150, 30, 40), BLUE)}))
    assert lock.state is LockState.LOST and hidden.outcome.vector is None and hidden.outcome.box is None
    blue = lock.steer(frame(5, {5: ((40, 150, 30, 40), BLUE), 8: ((100, 100, 30, 40), BLUE)}))  # a new blue car
    assert lock.state is LockState.LOST and blue.outcome.vector is None
    back = lock.steer(frame(6, {5: ((40, 150, 30, 40), BLUE), 8: ((100, 100, 30, 40), BLUE),
                                9: ((230, 70, 44, 33), DIM_RED)}))
    assert lock.state is LockState.LOCKED and lock.track_id == 9 and back.outcome.box == (230, 70, 44, 33)
    assert back.outcome.vector is not None and lock.status().renumbered == 1
    assert any("lock: #3 car is now #9" in e.message for e in events.recent)


def test_a_track_seen_beside_the_locked_one_is_never_taken_for_it() -> None:
    lock, _ = locked()
    lock.steer(frame(1, {3: ((200, 60, 40, 30), RED), 5: ((40, 150, 30, 40), RED)}))  # two red cars
    lock.steer(frame(2, {5: ((40, 150, 30, 40), RED)}))
    assert lock.state is LockState.LOST


def test_a_lock_lost_longer_than_lost_after_s_is_released() -> None:
    lock, events = locked(lost_after_s=1.0)
    lock.steer(frame(1, {3: ((200, 60, 40, 30), RED)}))
    for n in range(2, 12):
        lock.steer(frame(n, {}))
    assert lock.state is LockState.LOST and str(lock.status()) == "#3 car lost 1.0 s"
    lock.steer(frame(12, {}))
    assert lock.state is LockState.OFF and lock.track_id is None
    assert any("lock on #3 car released: not seen for 1 s (lost_after_s)" in e.message for e in events.recent)
    after = lock.steer(frame(13, {3: ((200, 60, 40, 30), RED)}))
    assert after.outcome.vector == (0.3, 0.0, 1.0) and after.outcome.box is None  # the processor's own again


def test_without_lost_after_s_a_lost_lock_waits() -> None:
    lock, _ = locked(lost_after_s=0.0)
    lock.steer(frame(1, {3: ((200, 60, 40, 30), RED)}))
    for n in range(2, 200):
        lock.steer(frame(n, {}))
    assert lock.state is LockState.LOST


def test_release() -> None:
    lock, events = locked()
    assert lock.release("operator", "test") and lock.state is LockState.OFF
    assert not lock.release("operator", "test")
    assert events.recent[-1].message == "lock on #3 car released: operator" and events.recent[-1].origin == "test"


def test_a_point_picks_the_smallest_track_box_that_holds_it() -> None:
    lock = TrackLock(EventLog(), lambda: 0.0)
    lock.steer(frame(0, {1: ((0, 0, 200, 200), RED), 2: ((50, 50, 20, 20), BLUE)}))
    assert lock.track_at(55, 60) == 2 and lock.track_at(150, 150) == 1 and lock.track_at(250, 10) is None


def test_looks_tell_the_same_car_from_another() -> None:
    red = frame(0, {1: ((10, 10, 60, 30), RED), 2: ((100, 10, 60, 30), DIM_RED), 3: ((200, 10, 60, 30), BLUE)})
    image = red.frame.image
    a, b, c = (look(image, box) for box in ((10, 10, 60, 30), (100, 10, 60, 30), (200, 10, 60, 30)))
    assert a is not None and b is not None and c is not None
    assert likeness(a, b) >= SAME_LOOK > likeness(a, c)
    assert look(image, (318, 238, 2, 2)) is None or look(image, (330, 10, 5, 5)) is None


def test_the_overlay_numbers_each_track_and_marks_the_lock() -> None:
    lock, _ = locked()
    result = lock.steer(frame(1, {3: ((200, 60, 40, 30), RED), 5: ((40, 150, 30, 40), BLUE)}))
    image = result.frame.image
    draw_tracks(image, result.outcome.detections, lock.status(), lock.vector)
    below_blue = image[190:205, 40:70]
    assert (below_blue == NUMBER_COLOUR).all(axis=2).sum() > 10  # "#5" under its box
    assert (image[58:62, 200:240] == LOCK_COLOUR).all(axis=2).sum() > 40  # the locked box's top edge


def test_the_shipped_yolos_frame_shows_the_numbers_the_platform_gave() -> None:
    """The bug this overlay fixes: ``yolo`` draws its boxes while it processes a frame, before the platform numbers
    them; the number is drawn after, under the box, on the frame the interfaces show."""
    photo = np.ascontiguousarray(data.astronaut()[..., ::-1])
    detector, tracks, lock = YoloDetector(), DetectionTracks(), TrackLock(EventLog(), lambda: 0.0)
    for n in range(3):
        image = np.roll(photo, 4 * n, axis=1)
        outcome = call_frame(detector, image, vector=False, tracks=tracks, seen_ns=n * 100_000_000)
        result = lock.steer(ProcessedFrame(Frame(image, n + 1, n * 100_000_000, 0),
                                           FrameOutcome(0, 0, detections=outcome.detections)))
        before = image.copy()
        draw_tracks(image, result.outcome.detections, lock.status(), lock.vector)
    person = next(found for found in result.outcome.detections or () if found.label == "person")
    x, y, w, h = person.box
    below = image[y + h:y + h + 14, x:x + 40] != before[y + h:y + h + 14, x:x + 40]
    assert person.track_id is not None and below.any(axis=2).sum() > 20  # "#0" under her box
    assert lock.lock(person.track_id, None) == f"locked on track #{person.track_id} (person)"


def test_a_lost_lock_compares_only_the_new_tracks_nearest_where_it_went() -> None:
    lock, _ = locked()
    lock.steer(frame(1, {3: ((200, 60, 40, 30), RED)}))
    near_blues = {10 + i: ((150 + 30 * (i % 2), 100 + 45 * (i // 2), 25, 35), BLUE) for i in range(NEAREST)}
    lock.steer(frame(2, {**near_blues, 20: ((10, 200, 40, 30), RED)}))  # alike, but the farthest of five
    assert lock.state is LockState.LOST
    lock.steer(frame(3, {**near_blues, 21: ((205, 62, 40, 30), RED)}))  # alike and where it went
    assert lock.state is LockState.LOCKED and lock.track_id == 21


def test_the_lock_gets_its_sim_car_back_under_a_new_number_after_the_tracker_dropped_it() -> None:
    """The ``sim:`` camera's frames, 30 m up near home looking down, three cars at 1 m/s; the detector (the cars' true
    boxes) sees nothing for 2.5 s, longer than the tracker keeps a track: every car comes back with a new number, and
    the lock takes its car back by its look and where it went, not the others (which look alike: the same roof)."""
    camera, pose = PinholeCamera(640, 480, 62.0), Pose(n=-2.0, e=-3.0, d=-30.0)
    renderer = SimRenderer(camera, default_ground(0), default_targets(3, 1.0), 2.0, 0)
    tracks, lock = DetectionTracks(), TrackLock(EventLog(), lambda: 0.0)
    numbers: dict[int, set[int]] = {0: set(), 1: set(), 2: set()}
    for n, t in enumerate(np.arange(4.0, 11.0, 0.1)):
        image = renderer.render(pose, float(t), n % 4)
        cars = [] if 6.0 <= t < 8.5 else [
            (car, cv2.boundingRect(np.array([project_ground_point(p, q, pose, camera) for p, q in target.corners(t)],
                                            np.float32))) for car, target in enumerate(renderer.targets)]
        cars = [(car, box) for car, box in cars if box[0] > 0 and box[1] > 0 and box[0] + box[2] < 640
                and box[1] + box[3] < 480]
        found = tracks.assign(tuple(Detected(box, "car", 0.9) for _, box in cars), round(t * 1e9))
        for (car, _), seen in zip(cars, found or (), strict=True):
            numbers[car].add(seen.track_id)
        lock.steer(ProcessedFrame(Frame(image, n + 1, round(t * 1e9), 0), FrameOutcome(0, 0, detections=found)))
        if n == 5:
            lock.lock(next(d.track_id for (car, _), d in zip(cars, found or (), strict=True) if car == 0), None)
    assert len(numbers[0]) == len(numbers[1]) == 2, numbers  # both in view renumbered by the gap (the third left)
    assert lock.state is LockState.LOCKED and lock.renumbered == 1 and lock.track_id == max(numbers[0])
