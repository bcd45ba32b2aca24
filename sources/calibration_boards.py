"""Calibration targets that find themselves in a frame: a chessboard (as OpenCV's calibration sample) or a ChArUco
board (markers between the squares: a view may show part of it)."""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

View = tuple[np.ndarray, np.ndarray]
"""One view of a board: (object points N x 1 x 3 in metres on the board's plane, image points N x 1 x 2), float32."""

_SUBPIX_WINDOW = (5, 5)
"""Half-size of cornerSubPix's search window, px: under half a square of a board a few metres away."""
_SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.001)
MIN_CHARUCO_CORNERS = 6
"""Fewer ChArUco corners than this in a view say too little about the lens."""


@dataclass(frozen=True)
class Chessboard:
    """A printed chessboard of ``corners`` = (columns, rows) inner corners, squares of ``square_m``."""

    corners: tuple[int, int] = (9, 6)
    square_m: float = 0.025
    _points: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        columns, rows = self.corners
        grid = np.mgrid[0:columns, 0:rows].T.reshape(-1, 2) * self.square_m
        object.__setattr__(self, "_points", np.column_stack([grid, np.zeros(len(grid))]).astype(np.float32)
                           .reshape(-1, 1, 3))

    def describe(self) -> str:
        return f"{self.corners[0]}x{self.corners[1]} chessboard (inner corners)"

    def advice(self) -> str:
        columns, rows = self.corners
        return (f"show the whole board, flat, well lit, filling a good part of the frame; --board is its inner "
                f"corners: {columns}x{rows} for a board of {columns + 1}x{rows + 1} squares")

    def find(self, image: np.ndarray) -> View | None:
        """All inner corners, sub-pixel, or None. As OpenCV's sample: ``findChessboardCorners`` (with a fast check:
        a frame without a board costs ~10 ms on a PC), then ``cornerSubPix``."""
        gray = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
        found, corners = cv2.findChessboardCorners(gray, self.corners, flags=cv2.CALIB_CB_ADAPTIVE_THRESH |
                                                   cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_FAST_CHECK)
        if not found:
            return None
        return self._points, cv2.cornerSubPix(gray, corners, _SUBPIX_WINDOW, (-1, -1), _SUBPIX_CRITERIA)

    def file_fields(self) -> dict[str, int | float | str]:
        return {"board_type": "chessboard", "board_width": self.corners[0], "board_height": self.corners[1],
                "square_size": self.square_m}


@dataclass(frozen=True)
class CharucoBoard:
    """A ChArUco board of ``squares`` = (columns, rows) squares, markers of ``marker_m`` from ``dictionary``."""

    squares: tuple[int, int] = (7, 5)
    square_m: float = 0.04
    marker_m: float = 0.03
    dictionary: str = "DICT_4X4_50"
    _board: cv2.aruco.CharucoBoard = field(init=False, repr=False, compare=False)
    _detector: cv2.aruco.CharucoDetector = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not self.dictionary.startswith("DICT_") or not hasattr(cv2.aruco, self.dictionary):
            known = ", ".join(name for name in dir(cv2.aruco) if name.startswith("DICT_"))
            raise ValueError(f"unknown ArUco dictionary {self.dictionary!r}; OpenCV's are {known}")
        if not 0 < self.marker_m < self.square_m:
            raise ValueError(f"the marker ({self.marker_m:g} m) must be smaller than the square ({self.square_m:g} m)")
        dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, self.dictionary))
        board = cv2.aruco.CharucoBoard(self.squares, self.square_m, self.marker_m, dictionary)
        object.__setattr__(self, "_board", board)
        object.__setattr__(self, "_detector", cv2.aruco.CharucoDetector(board))

    def describe(self) -> str:
        return f"{self.squares[0]}x{self.squares[1]} ChArUco board ({self.dictionary})"

    def advice(self) -> str:
        return (f"show the board (at least {MIN_CHARUCO_CORNERS} corners between markers), flat, well lit; --board is "
                f"its squares ({self.squares[0]}x{self.squares[1]}) and --dictionary its markers' ({self.dictionary})")

    def image(self, size: tuple[int, int]) -> np.ndarray:
        """The board drawn at ``size`` pixels (to print it)."""
        return self._board.generateImage(size)

    def find(self, image: np.ndarray) -> View | None:
        """The corners between squares that are seen (at least :data:`MIN_CHARUCO_CORNERS`), or None."""
        gray = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
        corners, ids, _, _ = self._detector.detectBoard(gray)
        if corners is None or ids is None or len(ids) < MIN_CHARUCO_CORNERS:
            return None
        # The ChArUco corners as one N x 1 x 2 array, as detectBoard returns them (the stub wants a sequence).
        objects, points = self._board.matchImagePoints(corners, ids)  # type: ignore[call-overload]
        return objects.astype(np.float32), points.astype(np.float32)

    def file_fields(self) -> dict[str, int | float | str]:
        return {"board_type": "charuco", "board_width": self.squares[0], "board_height": self.squares[1],
                "square_size": self.square_m, "marker_size": self.marker_m, "dictionary": self.dictionary}


Board = Chessboard | CharucoBoard
