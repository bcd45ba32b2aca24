"""``uav-tui calibrate --source URI``: views of a chessboard -> an OpenCV calibration file, with its RMS error.

As OpenCV's calibration sample: frames where the whole board is found are kept as views (one per ``--interval``,
and only when the board has moved since the last, so the views differ), then ``cv2.calibrateCamera`` and
``cv2.FileStorage``. Headless: progress, the number of views and the RMS are printed lines.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

import numpy as np

from sources import open_source
from sources.base import CameraSource
from sources.calibration import calibrate, find_corners, write_calibration
from uav_tui.arguments import ArgumentParser
from uav_tui.config import find_config_file, load_config
from uav_tui.errors import KNOWN_ERRORS, ConfigError, error_line
from uav_tui.text import safe

HINT_EVERY_S = 5.0
"""How often the advice is repeated while no board is found."""
MIN_MOVE = 0.05
"""A view is kept only when the board's corners moved by this share of the image width since the last view."""
GOOD_RMS_PX = 1.0
"""Above this RMS reprojection error the result is kept but said to be poor."""


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(prog="uav-tui calibrate", description=(
        "Calibrate a camera from views of a printed chessboard; writes the OpenCV calibration file that "
        "camera_calibration ([camera]) takes. Hold the board in front of the camera and move it between views: "
        "near and far, all over the image, tilted up to about 45 degrees."))
    parser.add_argument("--source", metavar="URI", help="camera URI (default: source of the configuration)")
    parser.add_argument("--config", metavar="PATH", help="TOML file to take source from")
    parser.add_argument("--board", default="9x6", metavar="COLSxROWS",
                        help="inner corners of the chessboard: squares minus one each way (default: 9x6, a 10x7 board)")
    parser.add_argument("--square", type=float, default=0.025, metavar="M", help="side of one square in metres "
                        "(default: 0.025; only the mounting's offsets use it, the intrinsics do not)")
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
        board = _board(args.board)
        if not 3 <= args.views <= 200 or not 0 < args.square <= 1 or args.interval < 0 or args.timeout <= 0:
            raise ConfigError("--views must be 3..200, --square 0 < M <= 1, --interval >= 0, --timeout > 0",
                              key="views")
        uri = args.source or load_config(find_config_file(args.config)).source
        source = open_source(uri)
    except KNOWN_ERRORS as exc:
        print(safe(error_line(exc, "uav-tui calibrate"), multiline=True), file=sys.stderr)
        return 2
    try:
        views, size = _collect(source, board, args.views, args.interval, args.timeout)
        if len(views) < args.views:
            return 1
        calibration = calibrate(views, board, args.square, size)
        write_calibration(args.out, calibration, board=board, square_m=args.square)
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


def _collect(source: CameraSource, board: tuple[int, int], wanted: int, interval_s: float,
             timeout_s: float) -> tuple[list[np.ndarray], tuple[int, int]]:
    """Keep views of the board until ``wanted`` or the timeout; prints progress and advice."""
    print(safe(f"looking for a {board[0]}x{board[1]} chessboard (inner corners) in {source!r}; "
               f"{wanted} views wanted"), flush=True)
    views: list[np.ndarray] = []
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
        corners = find_corners(image, board)
        now = time.monotonic()
        if corners is None:
            if now - max(last_seen, hinted) >= HINT_EVERY_S:
                hinted = now
                print(f"no {board[0]}x{board[1]} board found for {now - last_seen:.0f} s: show the whole board, flat, "
                      f"well lit, filling a good part of the frame; --board is its inner corners: "
                      f"{board[0]}x{board[1]} for a board of {board[0] + 1}x{board[1] + 1} squares", flush=True)
            continue
        last_seen = now
        frame_t = frame.t_mono_ns / 1e9
        if frame_t - last_view_t < interval_s:
            continue
        if views and float(np.mean(np.linalg.norm(corners - views[-1], axis=2))) < MIN_MOVE * size[0]:
            continue  # the same view again: wait for the board to move
        views.append(corners)
        last_view_t = frame_t
        print(f"view {len(views)}/{wanted}: board found", flush=True)
    assert size is not None or not views
    return views, size or (0, 0)


def _board(text: str) -> tuple[int, int]:
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not match or not all(3 <= int(n) <= 50 for n in match.groups()):
        raise ConfigError(f"--board {text!r} must be COLSxROWS inner corners, each 3..50 (e.g. 9x6)", key="board")
    return int(match[1]), int(match[2])
