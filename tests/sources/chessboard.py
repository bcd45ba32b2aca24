"""A chessboard seen by a camera: views rendered with a camera model's intrinsics, as the sim: renderer warps."""

from __future__ import annotations

import cv2
import numpy as np

from sources.camera_model import CameraModel

BOARD = (9, 6)
"""Inner corners (columns, rows) of the rendered board: 10 x 7 squares."""
SQUARE_M = 0.03
_PX = 40
"""Texture pixels per square."""


def _texture() -> np.ndarray:
    columns, rows = BOARD
    texture = np.full(((rows + 3) * _PX, (columns + 3) * _PX), 255, np.uint8)
    for r in range(rows + 1):
        for c in range(columns + 1):
            if (r + c) % 2 == 0:
                texture[(r + 1) * _PX:(r + 2) * _PX, (c + 1) * _PX:(c + 2) * _PX] = 0
    return texture


def render_views(model: CameraModel, count: int, seed: int = 0) -> list[np.ndarray]:
    """``count`` BGR views of the board in random poses 0.45-0.7 m away, tilted up to ~30 degrees."""
    texture = _texture()
    # texture pixels -> board metres, the first inner corner at the origin
    board_from_texture = np.array([[SQUARE_M / _PX, 0, -2 * SQUARE_M], [0, SQUARE_M / _PX, -2 * SQUARE_M], [0, 0, 1]])
    centre = np.array([(BOARD[0] - 1) / 2 * SQUARE_M, (BOARD[1] - 1) / 2 * SQUARE_M, 0.0])
    rng = np.random.default_rng(seed)
    views = []
    for _ in range(count):
        rotation, _ = cv2.Rodrigues(np.array([rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-0.3, 0.3)]))
        shift = np.array([rng.uniform(-0.08, 0.08), rng.uniform(-0.06, 0.06), rng.uniform(0.45, 0.7)])
        t = shift - rotation @ centre
        image_from_board = model.matrix @ np.column_stack([rotation[:, 0], rotation[:, 1], t])
        gray = cv2.warpPerspective(texture, image_from_board @ board_from_texture, (model.width, model.height),
                                   flags=cv2.INTER_AREA, borderValue=128)
        views.append(cv2.cvtColor(gray, cv2.COLOR_GRAY2BGR))
    return views
