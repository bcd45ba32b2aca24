"""The operator's lock on a track (issue 50): what it costs the loop a frame, and how well a look tells cars apart.

Cost, each the median of many calls on this machine: a look (:func:`uav_tui.flight.appearance.look`) by box size and
a comparison of two; :meth:`uav_tui.flight.track_lock.TrackLock.steer` a frame while locked and while lost with
every other detection a new track to compare (the worst case: 31 new tracks at once), and locked with the camera on
the gimbal (its rates instead of a vector); the platform's overlay
(:func:`uav_tui.flight.track_overlay.draw_tracks`) for 3, 10 and 32 numbered detections and the lock, on 640x480.
Looks: the likeness of the ``sim:`` camera's car to itself 2 s later (it has turned), to another car (the simulator
draws all cars with one roof: a look cannot tell them apart, only their numbers and where they were can) and to the
ground beside it; and of a red and a blue car on grey, the second in a shadow.

Usage: python scripts/bench_lock.py > scripts/results/lock.json
"""

from __future__ import annotations

import json
import platform
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sources.buffer import Frame  # noqa: E402
from sources.ground import default_ground  # noqa: E402
from sources.sim_geometry import PinholeCamera, Pose, project_ground_point  # noqa: E402
from sources.sim_render import SimRenderer, default_targets  # noqa: E402
from uav_tui.events import EventLog  # noqa: E402
from uav_tui.flight.appearance import likeness, look  # noqa: E402
from uav_tui.flight.track_lock import LockState, TrackLock  # noqa: E402
from uav_tui.flight.track_overlay import draw_tracks  # noqa: E402
from uav_tui.hosting.host import ProcessedFrame  # noqa: E402
from uav_tui.hosting.wire import FrameOutcome  # noqa: E402
from uav_values.camera import CameraModel, Mount  # noqa: E402
from uav_values.detections import Detected  # noqa: E402

CALLS = 2000


def median_us(call: Callable[[], object], calls: int = CALLS) -> float:
    times = []
    for _ in range(calls):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return round(statistics.median(times) * 1e6, 1)


def picture() -> np.ndarray:
    return np.random.default_rng(0).integers(0, 255, (480, 640, 3), np.uint8)


def boxes(count: int) -> list[tuple[int, int, int, int]]:
    return [(20 + 60 * (i % 10), 20 + 110 * (i // 10), 50, 30) for i in range(count)]


def steer_us(count: int, *, lost: bool, camera: CameraModel | None = None) -> float:
    """``steer`` a frame with ``count`` detections, locked on the first (or it missing and the rest new tracks), seen
    by ``camera`` (on the gimbal: the lock makes the gimbal's rates instead of a vector)."""
    image, events = picture(), EventLog()
    found = tuple(Detected(box, "car", 0.9, track_id=i) for i, box in enumerate(boxes(count)))
    x, y, w, h = found[0].box
    image[y:y + h, x:x + w] = (40, 40, 200)  # a red car among noise: no new track looks like it
    lock = TrackLock(events, lambda: 0.0)
    lock.steer(ProcessedFrame(Frame(image, 1, 0, 0), FrameOutcome(0, 0, detections=found[:1])))
    lock.lock(0, camera)
    lock.steer(ProcessedFrame(Frame(image, 2, 1, 0), FrameOutcome(0, 0, detections=found[:1])))  # its look is kept
    shown = found[1:] if lost else found
    n = [2]

    def one() -> None:
        n[0] += 1
        lock.steer(ProcessedFrame(Frame(image, n[0], n[0], 0), FrameOutcome(0, 0, detections=shown)))
    us = median_us(one, 500)
    assert lock.track_id == 0 and lock.state is (LockState.LOST if lost else LockState.LOCKED), lock.status()
    return us


def overlay_us(count: int) -> float:
    image, lock = picture(), TrackLock(EventLog(), lambda: 0.0)
    found = tuple(Detected(box, "car", 0.9, track_id=i) for i, box in enumerate(boxes(count)))
    lock.steer(ProcessedFrame(Frame(image, 1, 0, 0), FrameOutcome(0, 0, detections=found)))
    lock.lock(0, None)
    status = lock.status()
    return median_us(lambda: draw_tracks(image, found, status, (0.5, 0.2, 0.5)), 500)


def sim_looks() -> dict[str, float]:
    """Likeness of the sim camera's car 0 (from 25 m up, looking down) to itself 2 s later, to car 1, to ground."""
    camera = PinholeCamera(640, 480, 62.0)
    pose = Pose(n=0.0, e=0.0, d=-25.0)
    renderer = SimRenderer(camera, default_ground(0), default_targets(3, 1.0), 2.0, 0)

    def car_box(t: float, car: int) -> tuple[int, int, int, int]:
        corners = [project_ground_point(n, e, pose, camera) for n, e in renderer.targets[car].corners(t)]
        us, vs = zip(*corners, strict=True)
        return round(min(us)), round(min(vs)), round(max(us) - min(us)), round(max(vs) - min(vs))

    now, later = renderer.render(pose, 10.0), renderer.render(pose, 12.0, 1)
    car, again, other = look(now, car_box(10.0, 0)), look(later, car_box(12.0, 0)), look(now, car_box(10.0, 1))
    x, y, w, h = car_box(10.0, 0)
    ground = look(now, (x + w + 10, y, w, h))
    assert car is not None and again is not None and other is not None and ground is not None
    return {"same car 2 s later": round(likeness(car, again), 3), "another car": round(likeness(car, other), 3),
            "the ground beside it": round(likeness(car, ground), 3)}


def coloured_looks() -> dict[str, float]:
    image = np.full((240, 320, 3), 110, np.uint8)
    rng = np.random.default_rng(1)
    for x, colour in ((10, (40, 40, 200)), (100, (30, 30, 150)), (200, (200, 60, 30))):
        image[10:40, x:x + 60] = colour
    image = np.clip(image + rng.normal(0, 6, image.shape), 0, 255).astype(np.uint8)
    red, shaded, blue = (look(image, (x, 10, 60, 30)) for x in (10, 100, 200))
    assert red is not None and shaded is not None and blue is not None
    return {"red car, in a shadow": round(likeness(red, shaded), 3), "red car, blue car": round(likeness(red, blue), 3)}


def main() -> int:
    image = picture()
    a, b = look(image, (10, 10, 60, 30)), look(image, (100, 100, 60, 30))
    assert a is not None and b is not None
    result: dict[str, Any] = {
        "machine": f"{platform.machine()} {platform.processor() or platform.system()}",
        "look_us": {f"{w}x{h}": median_us(lambda w=w, h=h: look(image, (100, 100, w, h)))
                    for w, h in ((40, 20), (60, 30), (120, 60), (300, 200))},
        "likeness_us": median_us(lambda: likeness(a, b)),
        "steer_us": {f"locked, {n} detections": steer_us(n, lost=False) for n in (3, 10, 32)}
        | {f"lost, {n - 1} new tracks": steer_us(n, lost=True) for n in (3, 10, 32)}
        | {"locked on the gimbal, 3 detections": steer_us(3, lost=False, camera=CameraModel.from_hfov(
            640, 480, 62.0, Mount(0.0, gimbal=True)))},
        "overlay_us": {f"{n} numbers and the lock": overlay_us(n) for n in (3, 10, 32)},
        "likeness": {"sim: camera": sim_looks(), "coloured cars on grey": coloured_looks()},
    }
    print(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
