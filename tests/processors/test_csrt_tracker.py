"""CSRTTrackingProcessor on a generated sequence with a known target trajectory."""

from __future__ import annotations

import numpy as np
import pytest

from processors.csrt_tracker import CSRTTrackingProcessor
from processors.steering import normalised_offset
from processors.synthetic import TrackingSequence, iou, tracking_sequence

REACQUIRE_WITHIN = 4
"""Frames after the full occlusion ends by which the target must be tracked again."""


@pytest.fixture(scope="module")
def seq() -> TrackingSequence:
    return tracking_sequence((320, 240), 80)


def _run(proc: CSRTTrackingProcessor, seq: TrackingSequence) -> tuple[list, list]:
    proc._ramp = lambda vector, now: vector  # type: ignore[assignment]  # its direction, not its easing in
    proc.catch_cmd(tuple(int(v) for v in seq.boxes[0]))
    boxes, vectors = [], []
    for frame in seq.frames:
        proc.photo_processing(frame.copy())
        boxes.append(proc.box)
        vectors.append(proc.getPreparedVector())
    return boxes, vectors


@pytest.fixture(scope="module", params=["fast", "paper"])
def run(request: pytest.FixtureRequest, seq: TrackingSequence) -> tuple[list, list]:
    return _run(CSRTTrackingProcessor(mode=request.param), seq)


def test_mean_iou_over_visible_frames(run: tuple[list, list], seq: TrackingSequence) -> None:
    boxes, _ = run
    ious = [iou(b, t) for b, t in zip(boxes, seq.boxes, strict=True) if t is not None]
    assert np.mean(ious) >= 0.6


def test_full_occlusion_is_detected_and_target_reacquired(run: tuple[list, list], seq: TrackingSequence) -> None:
    boxes, vectors = run
    occluded = [boxes[i] for i in seq.full]
    # confidence collapse: lost within two frames of the occluder arriving, no vector while lost
    assert all(b is None for b in occluded[2:])
    assert all(vectors[i] is None for i in seq.full[2:])
    back = next(i for i in range(seq.full.stop, len(boxes)) if iou(boxes[i], seq.boxes[i]) > 0.5)
    assert back - seq.full.stop <= REACQUIRE_WITHIN


def test_vector_points_toward_target(run: tuple[list, list], seq: TrackingSequence) -> None:
    boxes, vectors = run
    checked = 0
    for truth, vec in zip(seq.boxes, vectors, strict=True):
        if truth is None or vec is None:
            continue
        ex, ey = normalised_offset(truth, seq.size)
        vx, vy, t = vec
        assert 0 < t <= 2 and abs(vx) <= 1 and abs(vy) <= 1
        if abs(ex) > 0.15:  # target clearly right (left) of centre -> fly right (left)
            assert np.sign(vy) == np.sign(ex)
            checked += 1
        if abs(ey) > 0.15:  # nadir camera: target above centre -> fly forward
            assert np.sign(vx) == -np.sign(ey)
            checked += 1
    assert checked > 40


def test_overlay_is_drawn_in_place(seq: TrackingSequence) -> None:
    proc = CSRTTrackingProcessor()
    proc.catch_cmd(tuple(int(v) for v in seq.boxes[0]))
    frame = seq.frames[0].copy()
    proc.photo_processing(frame)
    assert (frame != seq.frames[0]).any()


def test_buttons_drop_target_and_change_gain(seq: TrackingSequence) -> None:
    proc = CSRTTrackingProcessor()
    assert proc.getPreparedVector() is None  # no target yet
    proc.catch_cmd(tuple(int(v) for v in seq.boxes[0]))
    proc.photo_processing(seq.frames[0].copy())
    proc.photo_processing(seq.frames[1].copy())
    assert proc.getPreparedVector() is not None
    gain = proc.steering.gain
    proc.customize_processing(3)
    assert proc.steering.gain == pytest.approx(gain * 1.25)
    proc.customize_processing(4)
    assert proc.steering.gain == pytest.approx(gain)
    proc.customize_processing(1)
    proc.photo_processing(seq.frames[2].copy())
    assert proc.getPreparedVector() is None and proc.box is None and not proc.lost


def test_reacquire_now_and_saves_through_tm_mgr(seq: TrackingSequence, tm_mgr) -> None:
    proc = CSRTTrackingProcessor()
    proc.tmMgr = tm_mgr
    proc.catch_cmd(tuple(int(v) for v in seq.boxes[0]))
    for frame in seq.frames[:3]:
        proc.photo_processing(frame.copy())
    proc.customize_processing(2)
    proc.photo_processing(seq.frames[3].copy())
    assert iou(proc.box, seq.boxes[3]) > 0.6
    assert tm_mgr.saved and tm_mgr.saved[-1][1]["event"] == "reacquired"
    assert tm_mgr.saved[-1][1]["inliers"] >= proc.min_inliers


def test_bad_arguments_are_refused() -> None:
    with pytest.raises(ValueError, match="mode"):
        CSRTTrackingProcessor(mode="slow")
    with pytest.raises(ValueError, match="camera"):
        CSRTTrackingProcessor(camera="sideways")
    with pytest.raises(ValueError, match="TrackerCSRT_Params has no field scales"):
        CSRTTrackingProcessor(csrt={"scales": 3})


def test_tracking_on_a_down_scaled_frame_reports_full_frame_boxes(seq: TrackingSequence) -> None:
    proc = CSRTTrackingProcessor(target_px=20)  # the 48-px target is tracked at 16 px: the frame shrunk by 3
    boxes, _ = _run(proc, seq)
    assert proc._shrink == 3 and seq.size[0] % 3  # 320 px: the work frame drops the last 2 columns
    visible = [iou(b, t) for b, t in zip(boxes[:seq.full.start], seq.boxes[:seq.full.start], strict=True)]
    assert np.mean(visible) >= 0.6


def test_roi_is_clipped_to_the_frame(seq: TrackingSequence) -> None:
    proc = CSRTTrackingProcessor()
    proc.catch_cmd((-50, -50, 40, 40))  # entirely outside: ignored
    proc.photo_processing(seq.frames[0].copy())
    assert proc.box is None and not proc.lost
    x, y, w, h = seq.boxes[0]
    proc.catch_cmd((int(x), int(y), 1000, int(h)))  # runs off the right edge: clipped
    proc.photo_processing(seq.frames[0].copy())
    assert proc.box is not None and proc.box[0] + proc.box[2] <= seq.size[0]
