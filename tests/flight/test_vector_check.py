"""Safety rule 1: vectors are validated and clamped before anything flies."""

from __future__ import annotations

import math

import numpy as np
import pytest

from uav_tui.config import SafetyConfig
from uav_tui.flight.autonomy import check_vector

SAFETY = SafetyConfig(max_speed=1.0, max_t=2.0)


@pytest.mark.parametrize(("raw", "expected"), [
    ((0.5, -0.5, 1.0), (0.5, -0.5, 1.0)),
    ([0.2, 0.1, 0.5], (0.2, 0.1, 0.5)),
    ((3.0, -7.0, 1.0), (1.0, -1.0, 1.0)),
    ((0.1, 0.1, 10.0), (0.1, 0.1, 2.0)),
    ((np.float32(0.25), np.int64(0), 1), (0.25, 0.0, 1.0)),
], ids=["plain", "list", "speed-clamped", "t-clamped", "numpy-scalars"])
def test_valid_vectors_are_clamped(raw, expected) -> None:
    vector, note = check_vector(raw, SAFETY)
    assert vector == expected
    assert bool(note) == (tuple(float(v) for v in raw) != expected)


@pytest.mark.parametrize("raw", [
    (math.nan, 0.0, 1.0), (0.0, math.inf, 1.0), (0.1, 0.1, -math.inf), (0.1, 0.1, 0.0), (0.1, 0.1, -1.0),
    (0.1, 0.1), (0.1, 0.1, 1.0, 0.0), "0.1 0.1 1", None, 5, ("0.1", 0.0, 1.0), (True, 0.0, 1.0),
    {"vx": 1}, np.array([0.1, 0.1, 1.0]),
], ids=["nan", "inf", "neg-inf-t", "zero-t", "negative-t", "two", "four", "string", "none", "int", "str-item",
        "bool", "dict", "ndarray"])
def test_invalid_vectors_are_rejected(raw) -> None:
    vector, reason = check_vector(raw, SAFETY)
    assert vector is None and reason.startswith("rejected")
