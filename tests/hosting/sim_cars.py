"""The ``sim:`` camera's three cars crossing, seen by a detector that reports their true boxes with noise (the
tracks test and ``scripts/bench_tracks.py``)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from sources.sim_camera import SimCameraSource
from sources.sim_geometry import Pose, project_ground_point
from sources.uri import SourceUri
from uav_tui.hosting.frame_call import call_frame
from uav_tui.hosting.tracks import DetectionTracks

SIM = "sim:?mount=forward&tilt=30&targets=3&target_speed=4"
"""Three cars on rings of 6, 12 and 18 m, seen from 30 m south of their centre, 15 m up, looking north: between
12.3 s and 13.3 s cars 0 and 1 cross (their left-to-right order in the image turns over)."""
POSE = Pose(n=-30.0, e=0.0, d=-15.0)
GAP_S = (12.3, 13.3)
"""The detector sees nothing for this second, while cars 0 and 1 cross."""
SPAN_S = (9.0, 17.0)


def truth_boxes(source: SimCameraSource, t: float, rng: np.random.Generator) -> list[tuple[int, tuple[float, ...]]]:
    """(car, box with 1.5 px noise) of each car wholly in the sim camera's image at ``t``."""
    cam, found = source.camera, []
    for car, target in enumerate(source.targets):
        corners = [project_ground_point(n, e, POSE, cam) for n, e in target.corners(t)]
        us, vs = zip(*(c for c in corners if c is not None), strict=True)
        x, y, w, h = np.array([min(us), min(vs), max(us) - min(us), max(vs) - min(vs)]) + rng.normal(0.0, 1.5, 4)
        if len(us) == 4 and x >= 0 and y >= 0 and x + w < cam.width and y + h < cam.height:
            found.append((car, (x, y, w, h)))
    return found


def track_ids(fps: float, tracks: DetectionTracks, seed: int = 1) -> tuple[dict[int, list[int | None]],
                                                                          dict[float, dict[int, float]]]:
    """Each car's ``track_id`` on every frame it was detected, and each frame's cars' left edges, over
    :data:`SPAN_S` at ``fps`` with the detector blind during :data:`GAP_S`; through ``call_frame`` as hosts call it."""
    source = SimCameraSource.from_uri(SourceUri.parse(SIM))
    rng = np.random.default_rng(seed)
    ids: dict[int, list[int | None]] = {}
    lefts: dict[float, dict[int, float]] = {}
    for t in np.arange(*SPAN_S, 1 / fps):
        truth = [] if GAP_S[0] <= t < GAP_S[1] else truth_boxes(source, t, rng)
        detector = SimpleNamespace(photo_processing=lambda frame: None,
                                   detections=[(box, "car", 0.9) for _, box in truth])  # a detector that sees all
        outcome = call_frame(detector, None, vector=False, tracks=tracks, seen_ns=round(t * 1e9))
        assert outcome.error is None and outcome.detections is not None, outcome.error
        for (car, box), found in zip(truth, outcome.detections, strict=True):
            ids.setdefault(car, []).append(found.track_id)
            lefts.setdefault(round(float(t), 3), {})[car] = box[0]
    return ids, lefts
