"""A landing pad for ``sim:``: an ArUco / AprilTag marker lying flat on the simulated ground.

The marker's black square (its outer black border included) is ``size_m`` on a side, centred at ``(n, e)``,
its top edge facing north, with a white quiet zone one module wide around it, as printed pads have.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np


def _dictionary(name: str) -> int:
    constant = "DICT_" + name.strip().upper().removeprefix("DICT_")
    value = getattr(cv2.aruco, constant, None)
    if not isinstance(value, int):
        raise ValueError(f"marker dictionary {name!r} is not one of OpenCV's (4x4_50, apriltag_36h11, ...)")
    return value


@dataclass(frozen=True)
class GroundMarker:
    """One marker on the ground: dictionary, id, side of the black square (m), centre (NED metres).

    Raises:
        ValueError: an unknown dictionary, an id the dictionary lacks, or a size outside 0.01..100 m.
    """

    dictionary: str = "4x4_50"
    marker_id: int = 0
    size_m: float = 0.5
    n: float = 0.0
    e: float = 0.0
    _bits: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        vocabulary = cv2.aruco.getPredefinedDictionary(_dictionary(self.dictionary))
        if not 0 <= self.marker_id < vocabulary.bytesList.shape[0]:
            raise ValueError(f"marker id {self.marker_id} is not in {self.dictionary} "
                             f"(ids 0..{vocabulary.bytesList.shape[0] - 1})")
        if not 0.01 <= self.size_m <= 100:
            raise ValueError(f"marker size {self.size_m:g} m must be 0.01..100")
        modules = vocabulary.markerSize + 2
        bits = cv2.aruco.generateImageMarker(vocabulary, self.marker_id, modules, borderBits=1)
        object.__setattr__(self, "_bits", cv2.copyMakeBorder(bits, 1, 1, 1, 1, cv2.BORDER_CONSTANT, value=255))

    @property
    def modules(self) -> int:
        """Modules across the black square (the marker's bits and its black border)."""
        return int(self._bits.shape[0]) - 2

    def patch_corners(self) -> np.ndarray:
        """Ground (n, e) of the patch's corners, quiet zone included: north-west, north-east, south-east, south-west."""
        half = self.size_m / 2 * (self.modules + 2) / self.modules
        return np.array([[self.n + half, self.e - half], [self.n + half, self.e + half],
                         [self.n - half, self.e + half], [self.n - half, self.e - half]])

    def patch(self, side_px: float) -> np.ndarray:
        """The marker as a BGR image with about two pixels per pixel it will cover (``side_px`` across on screen)."""
        module_px = min(64, max(2, math.ceil(2 * side_px / self._bits.shape[0])))
        big = cv2.resize(self._bits, None, fx=module_px, fy=module_px, interpolation=cv2.INTER_NEAREST)
        return cv2.cvtColor(big, cv2.COLOR_GRAY2BGR)


def parse_marker(dictionary: str, marker_id: int, size_m: float, at: str) -> GroundMarker:
    """A marker from the ``sim:`` URI's ``marker_dict``, ``marker``, ``marker_size``, ``marker_at=N,E``.

    Raises:
        ValueError: saying what is expected.
    """
    parts = at.replace(" ", "").split(",")
    try:
        n, e = (float(p) for p in parts)
    except ValueError:
        raise ValueError(f"marker_at={at!r} must be N,E in metres from home (e.g. 3,-1.5)") from None
    if not (math.isfinite(n) and math.isfinite(e) and abs(n) < 10_000 and abs(e) < 10_000):
        raise ValueError(f"marker_at={at!r} must be finite metres within 10 km of home")
    return GroundMarker(dictionary, marker_id, size_m, n, e)
