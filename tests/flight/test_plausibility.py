"""The relay's plausibility checks (issue 47): a landing target or a gimbal pointing that type-checks but cannot be
true, or was changed after it was built, is refused with a reason; a true one passes."""

from __future__ import annotations

import math

import pytest

from controllers.base import Telemetry
from controllers.landing_target_message import rotation_ned_body
from processors import GimbalPointing, LandingTarget
from uav_tui.flight.plausibility import REFUSALS_TO_STOP, LandingCheck, RefusalRun, _ned, judge_gimbal
from uav_values.camera import CameraModel

CAMERA = CameraModel.from_hfov(640, 480, 62.0)
"""Looking straight down, the top of the image to the nose: camera x = body right, y = body back, z = body down."""
AT_10_M = Telemetry(rel_alt_m=10.0, roll_deg=0.0, pitch_deg=0.0, yaw_deg=0.0, vn_ms=0.0, ve_ms=0.0, vd_ms=0.0)
PAD = LandingTarget((0.0, -3.0, 10.0), math.hypot(3.0, 10.0))
"""The pad 3 m ahead of a vehicle 10 m above it."""


def _judge(target: LandingTarget, seq: int = 5, t_ns: int = 0, check: LandingCheck | None = None,
           at: Telemetry = AT_10_M) -> str:
    judged = (check or LandingCheck()).judge(target, seq, t_ns, CAMERA, at)
    assert (judged.target is None) == bool(judged.reason)
    return judged.reason


def _changed(target: LandingTarget, **fields: object) -> LandingTarget:
    for name, value in fields.items():
        object.__setattr__(target, name, value)  # as a processor can, after the value type checked it
    return target


def test_a_true_target_passes_as_a_copy_the_processor_does_not_hold() -> None:
    target = LandingTarget(PAD.direction, PAD.distance_m)
    judged = LandingCheck().judge(target, 5, 0, CAMERA, AT_10_M)
    assert judged.reason == "" and judged.target == target and judged.target is not target
    assert _judge(LandingTarget(PAD.direction)) == ""  # no distance: the ray meets the ground


@pytest.mark.parametrize(("target", "says"), [
    (LandingTarget(PAD.direction, PAD.distance_m * 900), "puts the pad 9000.0 m below the camera"),
    (LandingTarget(PAD.direction, PAD.distance_m / 20), "below the camera, but the vehicle is 10.0 m above home"),
    (_changed(LandingTarget(PAD.direction, 10.0), direction=(0.0, -0.3, -1.0)), "z > 0"),
    (_changed(LandingTarget(PAD.direction, 10.0), distance_m=-10.0), "must be in (0, 10000] m"),
    (_changed(LandingTarget(PAD.direction, 10.0), distance_m=math.inf), "must be in (0, 10000] m"),
    (_changed(LandingTarget(PAD.direction, 10.0), direction=(0.0, math.nan, 1.0)), "3 finite numbers"),
    (_changed(LandingTarget(PAD.direction, 10.0), direction="down"), "could not convert"),
    (LandingTarget(PAD.direction, PAD.distance_m, frame_seq=4), "seen in frame 4, not this one"),
    (LandingTarget((math.tan(math.radians(50)), 0.0, 1.0), 13.0), "outside the camera's view"),
], ids=["900x", "20x-short", "behind", "negative", "infinite", "nan", "not-numbers", "old-frame", "out-of-view"])
def test_a_target_that_cannot_be_true_is_refused_saying_why(target: LandingTarget, says: str) -> None:
    assert says in _judge(target)


def test_the_pad_must_be_below_the_horizon_and_a_distance_needs_a_height() -> None:
    tilted = Telemetry(rel_alt_m=10.0, roll_deg=0.0, pitch_deg=80.0, yaw_deg=0.0)  # nose up 80: the camera looks ahead
    assert "below the horizon: a landing pad is below" in _judge(PAD, at=tilted)
    assert _judge(PAD, at=Telemetry()) == "no height at the capture to check the distance against"


def test_the_pad_may_not_jump_further_than_the_vehicles_speed_explains() -> None:
    check = LandingCheck()
    assert _judge(PAD, 1, 0, check) == ""
    jumped = LandingTarget((0.0, 3.0, 10.0), math.hypot(3.0, 10.0))  # 6 m behind where it was, 0.1 s later
    assert "the pad moved 6.0 m relative to the vehicle in 0.10 s" in _judge(jumped, 2, 100_000_000, check)
    assert _judge(PAD, 3, 200_000_000, check) == ""  # the refused one is no reference: the true one still fits
    moving = Telemetry(rel_alt_m=10.0, roll_deg=0.0, pitch_deg=0.0, yaw_deg=0.0, vn_ms=-20.0)
    assert _judge(jumped, 4, 500_000_000, check, moving) == ""  # 20 m/s for 0.3 s explains 6 m
    assert _judge(jumped, 5, 2_000_000_000, LandingCheck()) == ""  # no reference after JUMP_MEMORY_S


def test_a_run_of_refusals_says_stop_until_one_is_accepted() -> None:
    run = RefusalRun()
    assert not any(run.refuse("bad") for _ in range(REFUSALS_TO_STOP - 1))
    assert run.refuse("worse") and run.refuse("worse") and run.last == "worse"
    run.accept()
    assert not run.refuse("bad") and run.refused == REFUSALS_TO_STOP + 2


def test_a_gimbal_pointing_is_checked_again_against_the_contracts_ranges() -> None:
    pointing = GimbalPointing.angles(-45.0, 10.0)
    assert judge_gimbal(pointing) == pointing and judge_gimbal(pointing) is not pointing
    object.__setattr__(pointing, "pitch", 1e30)
    assert judge_gimbal(pointing) == "gimbal angle pitch=1e+30 deg is out of range [-90, 90]"
    object.__setattr__(pointing, "pitch", math.nan)
    assert "must be a finite number" in str(judge_gimbal(pointing))
    object.__setattr__(pointing, "mode", "spin")
    assert "must be 'rate' or 'angle'" in str(judge_gimbal(pointing))


def test_the_scalar_rotation_is_the_autopilots() -> None:
    body = (0.3, -0.5, 0.8)
    for attitude in ((0.0, 0.0, 0.0), (12.0, -7.0, 135.0), (-40.0, 25.0, -170.0)):
        assert _ned(body, *attitude) == pytest.approx(tuple(rotation_ned_body(*attitude) @ body))
