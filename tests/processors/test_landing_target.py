"""The contract's landing target: a unit direction in the camera frame, an optional distance, checked on build."""

from __future__ import annotations

import math

import pytest

from processors.outputs import STATUS_CHARS
from uav_tui.hosting.frame_call import call_frame
from uav_values.landing_target import CAMERA_FRAME, LandingTarget


def test_direction_is_normalised_and_angles_follow_it() -> None:
    target = LandingTarget((3.0, -4.0, 12.0), distance_m=6.5, frame_seq=42)
    assert target.direction == pytest.approx((3 / 13, -4 / 13, 12 / 13))
    assert target.angles == pytest.approx((math.atan2(3, 12), math.atan2(-4, 12)))
    assert target.position_m == pytest.approx((1.5, -2.0, 6.0))
    assert (target.frame, target.frame_seq) == (CAMERA_FRAME, 42)


def test_from_angles_round_trips() -> None:
    target = LandingTarget.from_angles(math.radians(10), math.radians(-20))
    assert target.angles == pytest.approx((math.radians(10), math.radians(-20)))
    assert target.distance_m is None and target.position_m is None


@pytest.mark.parametrize("direction", [(0.0, 0.0, 0.0), (0.0, 0.0, -1.0), (1.0, 0.0, 0.0), (math.nan, 0.0, 1.0)],
                         ids=["zero", "behind", "sideways", "nan"])
def test_a_direction_not_in_front_of_the_camera_is_refused(direction: tuple[float, float, float]) -> None:
    with pytest.raises(ValueError, match="z > 0"):
        LandingTarget(direction)


@pytest.mark.parametrize("distance", [0.0, -1.0, math.inf, 1e6], ids=["zero", "negative", "inf", "huge"])
def test_a_wrong_distance_is_refused(distance: float) -> None:
    with pytest.raises(ValueError, match="distance"):
        LandingTarget((0.0, 0.0, 1.0), distance)


def test_only_the_camera_frame_is_accepted() -> None:
    with pytest.raises(ValueError, match="frame"):
        LandingTarget((0.0, 0.0, 1.0), frame="body")


class _Returns:
    """A processor whose getLandingTarget returns ``value``."""

    def __init__(self, value: object) -> None:
        self.value = value

    def photo_processing(self, frame: object) -> None:
        pass

    def getLandingTarget(self) -> object:
        return self.value


def test_the_per_frame_call_reads_the_landing_target_and_refuses_anything_else() -> None:
    target = LandingTarget((0.0, 0.0, 2.0), 4.0)
    outcome = call_frame(_Returns(target), None, vector=False, outputs=["getLandingTarget"])
    assert outcome.outputs.landing_target == target and outcome.error is None
    assert call_frame(_Returns(target), None, vector=False).outputs.landing_target is None  # not asked: not called
    wrong = call_frame(_Returns((0.1, 0.2)), None, vector=False, outputs=["getLandingTarget"])
    assert wrong.outputs.landing_target is None
    assert wrong.raised.startswith("TypeError: getLandingTarget() returned tuple (0.1, 0.2): return a "
                                   "processors.LandingTarget or None")


@pytest.mark.parametrize("angle", [math.pi, -math.pi / 2, 2.0, math.inf], ids=["pi", "minus-half-pi", "2-rad", "inf"])
def test_from_angles_refuses_an_angle_a_tangent_would_fold_back_in_front(angle: float) -> None:
    with pytest.raises(ValueError, match=r"angle_x=.* must be within \(-pi/2, pi/2\)"):
        LandingTarget.from_angles(angle, 0.0, 5.0)  # tan(pi) is 0: it was taken as straight down


def test_a_target_returned_again_keeps_the_frame_it_was_first_returned_after() -> None:
    processor = _Returns(LandingTarget((0.0, 0.0, 2.0), 4.0))  # built once, returned after every frame
    first = call_frame(processor, None, vector=False, outputs=["getLandingTarget"], frame_seq=7)
    again = call_frame(processor, None, vector=False, outputs=["getLandingTarget"], frame_seq=8)
    assert first.outputs.landing_target.frame_seq == again.outputs.landing_target.frame_seq == 7
    own = LandingTarget((0.0, 0.0, 2.0), 4.0, frame_seq=3)  # the processor's own frame number is kept
    assert call_frame(_Returns(own), None, vector=False, outputs=["getLandingTarget"],
                      frame_seq=9).outputs.landing_target.frame_seq == 3


def test_without_a_target_the_processors_own_reason_is_read_as_one_bounded_line() -> None:
    processor = _Returns(None)
    processor.status = "2 markers with id 7:\x1b[2J which is the pad?\nno target" + " x" * 200  # type: ignore[attr-defined]
    outputs = call_frame(processor, None, vector=False, outputs=["getLandingTarget"]).outputs
    assert outputs.landing_status.startswith("2 markers with id 7: [2J which is the pad? no target x x")
    assert len(outputs.landing_status) == STATUS_CHARS and outputs.landing_status.endswith("...")
    processor.value = LandingTarget((0.0, 0.0, 2.0), 4.0)
    assert call_frame(processor, None, vector=False, outputs=["getLandingTarget"]).outputs.landing_status == ""
