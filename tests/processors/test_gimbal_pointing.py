"""The contract's gimbal pointing: rates or angles, checked on build; anything else is the processor's error."""

from __future__ import annotations

import math

import pytest

from processors import GimbalPointing
from processors.base import validate_processor
from uav_tui.hosting.frame_call import call_frame
from uav_values.gimbal import MAX_RATE_DEG_S


def test_rates_and_angles_keep_their_values_as_floats() -> None:
    rates = GimbalPointing.rates(-4, 12.5)
    assert (rates.mode, rates.pitch, rates.yaw) == ("rate", -4.0, 12.5) and isinstance(rates.pitch, float)
    angles = GimbalPointing.angles(-90.0)
    assert (angles.mode, angles.pitch, angles.yaw) == ("angle", -90.0, 0.0)
    assert rates.describe() == "rates pitch -4.0 yaw 12.5 deg/s"


@pytest.mark.parametrize(("build", "message"), [
    (lambda: GimbalPointing.rates(math.nan, 0.0), r"gimbal rate pitch=nan must be a finite number \(deg/s\)"),
    (lambda: GimbalPointing.rates(0.0, math.inf), r"gimbal rate yaw=inf must be a finite number"),
    (lambda: GimbalPointing.rates(MAX_RATE_DEG_S + 1, 0.0),
     r"gimbal rate pitch=181 deg/s is out of range \[-180, 180\]"),
    (lambda: GimbalPointing.angles(-91.0), r"gimbal angle pitch=-91 deg is out of range \[-90, 90\]"),
    (lambda: GimbalPointing.angles(0.0, 270.0), r"gimbal angle yaw=270 deg is out of range \[-180, 180\]"),
    (lambda: GimbalPointing.rates("1", 0.0), r"gimbal rate pitch='1' must be a finite number"),  # type: ignore[arg-type]
    (lambda: GimbalPointing.rates(True, 0.0), r"gimbal rate pitch=True must be a finite number"),
    (lambda: GimbalPointing("spin", 0.0, 0.0), r"mode 'spin' must be 'rate' or 'angle'"),  # type: ignore[arg-type]
], ids=["nan", "inf", "too-fast", "pitch-below", "yaw-beyond", "text", "bool", "mode"])
def test_bad_values_are_refused_with_a_clear_message(build: object, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        build()  # type: ignore[operator]


class _Points:
    """A processor whose getGimbalPointing returns ``value``."""

    def __init__(self, value: object) -> None:
        self.value = value

    def photo_processing(self, frame: object) -> None:
        pass

    def getGimbalPointing(self) -> object:
        return self.value


def test_the_method_is_detected_at_load_time() -> None:
    info = validate_processor(_Points(None), name="points", path=None)
    assert "getGimbalPointing" in info.capabilities


def test_the_per_frame_call_reads_the_pointing_and_refuses_anything_else() -> None:
    pointing = GimbalPointing.rates(1.0, -2.0)
    outcome = call_frame(_Points(pointing), None, vector=False, outputs=["getGimbalPointing"])
    assert outcome.outputs.gimbal == pointing and outcome.error is None
    assert call_frame(_Points(pointing), None, vector=False).outputs.gimbal is None  # not asked: not called
    wrong = call_frame(_Points((1.0, -2.0)), None, vector=False, outputs=["getGimbalPointing"])
    assert wrong.outputs.gimbal is None
    assert wrong.raised.startswith("TypeError: getGimbalPointing() returned tuple (1.0, -2.0): return "
                                   "processors.GimbalPointing.rates(pitch, yaw) or .angles(pitch, yaw), or None")
    nothing = call_frame(_Points(None), None, vector=False, outputs=["getGimbalPointing"])
    assert nothing.outputs.gimbal is None and nothing.error is None
