"""Normalized selections -> frame pixels."""

from __future__ import annotations

import pytest

from uav_tui.errors import CommandError
from uav_tui.web.roi import point_to_roi, rect_to_roi, roi_from_message


@pytest.mark.parametrize(("corners", "size", "expected"), [
    ((0.25, 0.3, 0.55, 0.7), (640, 480), (160, 144, 192, 192)),
    ((0.55, 0.7, 0.25, 0.3), (640, 480), (160, 144, 192, 192)),
    ((0.0, 0.0, 1.0, 1.0), (1280, 720), (0, 0, 1280, 720)),
    ((0.5, 0.5, 0.5, 0.5), (640, 480), (320, 240, 4, 4)),
    ((1.0, 1.0, 1.0, 1.0), (640, 480), (636, 476, 4, 4)),
], ids=["drag", "reversed-drag", "whole-frame", "zero-size-grows", "corner-stays-inside"])
def test_rect_to_roi(corners: tuple[float, ...], size: tuple[int, int], expected: tuple[int, ...]) -> None:
    assert rect_to_roi(*corners, size) == expected


@pytest.mark.parametrize(("point", "radius", "expected"), [
    ((0.5, 0.5), 0.0, (296, 216, 48, 48)),
    ((0.5, 0.5), 0.05, (288, 208, 64, 64)),
    ((0.0, 0.0), 0.0, (0, 0, 48, 48)),
    ((1.0, 1.0), 0.0, (592, 432, 48, 48)),
    ((0.5, 0.5), 1.0, (0, 0, 640, 480)),
], ids=["default-box", "mavlink-radius", "top-left", "bottom-right", "huge-radius-clipped"])
def test_point_to_roi(point: tuple[float, float], radius: float, expected: tuple[int, ...]) -> None:
    assert point_to_roi(*point, (640, 480), radius=radius) == expected


@pytest.mark.parametrize("message", [
    None, [], {}, {"rect": [0, 0, 1]}, {"rect": [0, 0, 1, 2]}, {"point": [0.5, float("nan")]},
    {"point": [0.5, float("inf")]}, {"point": [True, 0.5]}, {"rect": "0 0 1 1"},
], ids=["none", "list", "empty", "short", "out-of-range", "nan", "inf", "bool", "string"])
def test_bad_messages_are_command_errors(message: object) -> None:
    with pytest.raises(CommandError):
        roi_from_message(message, (640, 480))
