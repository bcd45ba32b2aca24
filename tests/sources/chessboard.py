"""Calibration boards seen by a camera: views rendered with a camera model's intrinsics, as the sim: renderer warps
its ground (a homography of the board's plane)."""

from __future__ import annotations

import cv2
import numpy as np

from sources.calibration_boards import CharucoBoard, Chessboard
from uav_values.camera import CameraModel

CHESSBOARD = Chessboard((9, 6), 0.03)
"""The rendered chessboard: 9x6 inner corners (10 x 7 squares) of 3 cm."""
CHARUCO = CharucoBoard((7, 5), 0.04, 0.03)
_PX = 40
"""Texture pixels per square."""


def _chessboard_texture() -> tuple[np.ndarray, np.ndarray]:
    """The board with one white square of margin, and the matrix from its pixels to board metres."""
    columns, rows = CHESSBOARD.corners
    texture = np.full(((rows + 3) * _PX, (columns + 3) * _PX), 255, np.uint8)
    for r in range(rows + 1):
        for c in range(columns + 1):
            if (r + c) % 2 == 0:
                texture[(r + 1) * _PX:(r + 2) * _PX, (c + 1) * _PX:(c + 2) * _PX] = 0
    square = CHESSBOARD.square_m
    return texture, np.array([[square / _PX, 0, -2 * square], [0, square / _PX, -2 * square], [0, 0, 1]])


def _charuco_texture() -> tuple[np.ndarray, np.ndarray]:
    columns, rows = CHARUCO.squares
    texture = cv2.copyMakeBorder(CHARUCO.image((columns * _PX, rows * _PX)), _PX, _PX, _PX, _PX,
                                 cv2.BORDER_CONSTANT, value=255)
    square = CHARUCO.square_m
    return texture, np.array([[square / _PX, 0, -square], [0, square / _PX, -square], [0, 0, 1]])


def render_views(model: CameraModel, count: int, seed: int = 0, *, charuco: bool = False, tilted: bool = True,
                 distance_m: tuple[float, float] = (0.45, 0.7)) -> list[np.ndarray]:
    """``count`` BGR views of the board in random poses ``distance_m`` away, tilted up to ~30 degrees (``tilted``)
    or square to the camera and moved over the whole image (not ``tilted``)."""
    texture, board_from_texture = _charuco_texture() if charuco else _chessboard_texture()
    height, width = texture.shape
    centre = board_from_texture @ np.array([width / 2, height / 2, 1.0])
    centre = np.array([centre[0], centre[1], 0.0])
    rng = np.random.default_rng(seed)
    spread = 1.0 if tilted else 1.6
    views = []
    for _ in range(count):
        angles = [rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-0.3, 0.3)]
        rotation, _ = cv2.Rodrigues(np.array(angles if tilted else [0.0, 0.0, angles[2]]))
        shift = np.array([rng.uniform(-0.08, 0.08) * spread, rng.uniform(-0.06, 0.06) * spread,
                          rng.uniform(*distance_m)])
        t = shift - rotation @ centre
        image_from_board = model.matrix @ np.column_stack([rotation[:, 0], rotation[:, 1], t])
        gray = cv2.warpPerspective(texture, image_from_board @ board_from_texture, (model.width, model.height),
                                   flags=cv2.INTER_AREA, borderValue=128)
        views.append(cv2.cvtColor(gray, cv2.COLOR_GRAY2BGR))
    return views
