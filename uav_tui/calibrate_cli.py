"""``uav-tui calibrate --source URI``: views of a chessboard (or ChArUco board) -> an OpenCV calibration file, with
its RMS error.

As OpenCV's calibration sample: frames where the board is found are kept as views (one per ``--interval``, and only
when the board has moved since the last, so the views differ), then ``cv2.calibrateCamera`` and ``cv2.FileStorage``.
Headless: progress, the number of views and the RMS are printed lines.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

import cv2
import numpy as np

from sources import open_source
from sources.base import CameraSource
from sources.calibration import calibrate, write_calibration
from sources.calibration_boards import Board, CharucoBoard, Chessboard, View
from uav_tui.arguments import ArgumentParser
from uav_tui.config import find_config_file, load_config
from uav_tui.errors import KNOWN_ERRORS, ConfigError, error_line
from uav_tui.output.text import safe

HINT_EVERY_S = 5.0
"""How often the advice is repeated while no board is found."""
MIN_MOVE = 0.05
"""A view is kept only when the board's centre or size changed by this share of the image width since the last."""
GOOD_RMS_PX = 1.0
"""Above this RMS reprojection error the result is kept but said to be poor."""


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(prog="uav-tui calibrate", description=(
        "Calibrate a camera from views of a printed chessboard (or ChArUco board: --charuco); writes the OpenCV "
        "calibration file that camera_calibration ([camera]) takes. Hold the board in front of the camera and move "
        "it between views: near and far, all over the image, tilted up to about 45 degrees."))
    parser.add_argument("--charuco", action="store_true", help="the board is a ChArUco board (views may show part "
                        "of it); --write-board prints one")
    parser.add_argument("--source", metavar="URI", help="camera URI (default: source of the configuration)")
    parser.add_argument("--config", metavar="PATH", help="TOML file to take source from")
    parser.add_argument("--board", metavar="COLSxROWS", help="a chessboard's inner corners, squares minus one each "
                        "way (default: 9x6, a 10x7 board); a ChArUco board's squares (default: 7x5)")
    parser.add_argument("--square", type=float, metavar="M", help="side of one square in metres (default: 0.025; "
                        "ChArUco 0.04); the intrinsics do not depend on it")
    parser.add_argument("--marker", type=float, metavar="M", help="ChArUco: side of a marker in metres "
                        "(default: 3/4 of the square)")
    parser.add_argument("--dictionary", default="DICT_4X4_50", help="ChArUco: the markers' ArUco dictionary "
                        "(default: DICT_4X4_50)")
    parser.add_argument("--write-board", type=Path, metavar="PNG", help="ChArUco: write the board as an image to "
                        "print (100 px a square), then exit")
    parser.add_argument("--views", type=int, default=15, metavar="N", help="views to collect (default: 15)")
    parser.add_argument("--interval", type=float, default=1.0, metavar="S",
                        help="at least this long between two views, s (default: 1)")
    parser.add_argument("--timeout", type=float, default=300.0, metavar="S", help="give up after S s (default: 300)")
    parser.add_argument("--out", type=Path, default=Path("camera.yaml"), metavar="FILE",
                        help="file to write: .yaml, .json or .xml (default: camera.yaml)")
    return parser


def main(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    try:
        board = _board(args)
        if args.write_board is not None:
            return _write_board(board, args.write_board)
        if not 3 <= args.views <= 200 or args.interval < 0 or args.timeout <= 0:
            raise ConfigError("--views must be 3..200, --interval >= 0, --timeout > 0", key="views")
        uri = args.source or load_config(find_config_file(args.config)).source
        source = open_source(uri)
    except KNOWN_ERRORS as exc:
        print(safe(error_line(exc, "uav-tui calibrate"), multiline=True), file=sys.stderr)
        return 2
    try:
        views, size = _collect(source, board, args.views, args.interval, args.timeout)
        if len(views) < args.views:
            return 1
        calibration = calibrate(views, size)
        write_calibration(args.out, calibration, board)
    except KeyboardInterrupt:
        print("interrupted: nothing written", flush=True)
        return 130
    except KNOWN_ERRORS as exc:
        print(safe(error_line(exc, "uav-tui calibrate"), multiline=True), file=sys.stderr)
        return 1
    finally:
        source.close()
    k, d = calibration.matrix, calibration.distortion
    print(f"RMS reprojection error {calibration.rms_px:.3f} px over {len(views)} views of {size[0]}x{size[1]}")
    print(f"fx {k[0, 0]:.2f}  fy {k[1, 1]:.2f}  cx {k[0, 2]:.2f}  cy {k[1, 2]:.2f}  distortion "
          + " ".join(f"{c:.4f}" for c in d.ravel()))
    if calibration.rms_px is not None and calibration.rms_px > GOOD_RMS_PX:
        print(f"the RMS is above {GOOD_RMS_PX:g} px: the views were blurred or the board is not flat; calibrate "
              "again with a flat board, good light and a steady hand")
    print(safe(f"wrote {args.out}: use it with --camera-calibration {args.out} (or camera_calibration in [camera])"))
    return 0


def _collect(source: CameraSource, board: Board, wanted: int, interval_s: float,
             timeout_s: float) -> tuple[list[View], tuple[int, int]]:
    """Keep views of the board until ``wanted`` or the timeout; prints progress and advice."""
    print(safe(f"looking for a {board.describe()} in {source!r}; {wanted} views wanted"), flush=True)
    views: list[View] = []
    size: tuple[int, int] | None = None
    seq, last_view_t, last_seen = 0, -np.inf, time.monotonic()
    started = hinted = last_seen
    while len(views) < wanted:
        now = time.monotonic()
        if now - started > timeout_s:
            print(f"gave up after {timeout_s:g} s with {len(views)} of {wanted} views: nothing written", flush=True)
            break
        frame = source.buffer.wait_newer(seq, 1.0)
        if frame is None:
            continue
        seq, image = frame.seq, frame.image
        frame_size = (image.shape[1], image.shape[0])
        if size is not None and frame_size != size:
            raise ConfigError(f"the camera changed its frame size from {size[0]}x{size[1]} to "
                              f"{frame_size[0]}x{frame_size[1]}: calibrate again at one size", key="source")
        size = frame_size
        view = board.find(image)
        now = time.monotonic()
        if view is None:
            if now - max(last_seen, hinted) >= HINT_EVERY_S:
                hinted = now
                print(f"no board found for {now - last_seen:.0f} s: {board.advice()}", flush=True)
            continue
        last_seen = now
        frame_t = frame.t_mono_ns / 1e9
        if frame_t - last_view_t < interval_s:
            continue
        if views and _moved(views[-1][1], view[1]) < MIN_MOVE * size[0]:
            continue  # the same view again: wait for the board to move
        views.append(view)
        last_view_t = frame_t
        print(f"view {len(views)}/{wanted}: board found ({len(view[1])} corners)", flush=True)
    assert size is not None or not views
    return views, size or (0, 0)


def _moved(before: np.ndarray, after: np.ndarray) -> float:
    """How far (px) the board's centre moved or its size changed between two views' image points."""
    def centre_and_size(points: np.ndarray) -> tuple[np.ndarray, float]:
        flat = points.reshape(-1, 2)
        return flat.mean(axis=0), float(np.linalg.norm(flat.max(axis=0) - flat.min(axis=0)))
    (c0, s0), (c1, s1) = centre_and_size(before), centre_and_size(after)
    return max(float(np.linalg.norm(c1 - c0)), abs(s1 - s0))


def _board(args: argparse.Namespace) -> Board:
    default, what = ("7x5", "squares") if args.charuco else ("9x6", "inner corners")
    text = args.board or default
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not match or not all(3 <= int(n) <= 50 for n in match.groups()):
        raise ConfigError(f"--board {text!r} must be COLSxROWS {what}, each 3..50 (e.g. {default})", key="board")
    size = (int(match[1]), int(match[2]))
    square = args.square if args.square is not None else (0.04 if args.charuco else 0.025)
    if not 0 < square <= 1:
        raise ConfigError(f"--square {square:g} must be a side in metres, 0 < M <= 1", key="square")
    if not args.charuco:
        return Chessboard(size, square)
    try:
        return CharucoBoard(size, square, args.marker if args.marker is not None else 0.75 * square, args.dictionary)
    except ValueError as exc:
        raise ConfigError(f"--charuco: {exc}", key="board") from None


def _write_board(board: Board, path: Path) -> int:
    if not isinstance(board, CharucoBoard):
        raise ConfigError("--write-board draws ChArUco boards (--charuco); print any chessboard of the size you give "
                          "--board", key="write_board")
    image = board.image((100 * board.squares[0], 100 * board.squares[1]))
    if not cv2.imwrite(str(path), image):
        raise ConfigError(f"cannot write {path}: give a .png path in a folder that exists", key="write_board")
    print(safe(f"wrote {path}: print it at 100 % so a square is {board.square_m * 100:g} cm (measure it, and give "
               f"--square and --marker what you measured)"))
    return 0
