"""Build a covered-stretch copy of the aerial-tracking set: the target hidden for 2 s in each sequence.

    .venv/bin/python scripts/build_covered_set.py OUT [--set DIR] [--seconds 2] [--at 0.4] [--only FOLDER ...]

For each sequence of ``--set`` (default: the aerial-tracking set where the tests find it), from frame
``round(at * frames)`` (earlier where that leaves under 1 s after it) for ``seconds`` of its own time, the
target's ground-truth box (grown by :data:`MARGIN` a side) is painted over with the patch of the same size
beside it (the first of left, right, above, below that lies in the frame clear of the box), and those gt rows
are NaN. Every other frame and gt row is the original's (the video re-encoded, ``mp4v``, as the set's are). A
sequence too short to keep 1 s tracked before the stretch and 1 s after it is left out (the script says which).
Deterministic: the same set gives the same copy. ``uav-tui eval OUT`` scores it; ``cover.txt`` in each folder
says which frames are covered.
"""

from __future__ import annotations

import argparse
import math
import shutil
import sys
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from uav_tui.evaluation.sequences import (  # noqa: E402 - the repository's own package, found from the script
    VIDEO_GT,
    VIDEO_NAME,
    Sequence,
    aerial_tracking_set,
    find_sequences,
)

MARGIN = 0.15
"""Share of the box's size added on each side before painting: the box's edge pixels show the target too."""


def stretch(sequence: Sequence, seconds: float, at: float) -> range | None:
    """The covered frames of ``sequence``, or None when it cannot keep 1 s before and 1 s after them."""
    length, second = round(seconds * sequence.fps), round(sequence.fps)
    start = min(round(at * len(sequence)), len(sequence) - length - second)  # earlier where the end is near
    if start < second:
        return None
    return range(start, start + length)


def cover(image: np.ndarray, box: np.ndarray) -> np.ndarray:
    """``image`` with ``box`` (grown by :data:`MARGIN`) painted over by the patch of its size beside it."""
    x, y, w, h = box
    height, width = image.shape[:2]
    x0, y0 = max(int(math.floor(x - MARGIN * w)), 0), max(int(math.floor(y - MARGIN * h)), 0)
    x1, y1 = min(int(math.ceil(x + w + MARGIN * w)), width), min(int(math.ceil(y + h + MARGIN * h)), height)
    pw, ph = x1 - x0, y1 - y0
    if pw <= 0 or ph <= 0:
        return image
    for dx, dy in ((-pw, 0), (pw, 0), (0, -ph), (0, ph)):
        sx, sy = x0 + dx, y0 + dy
        if min(sx, sy) >= 0 and sx + pw <= width and sy + ph <= height:
            image[y0:y1, x0:x1] = image[sy:sy + ph, sx:sx + pw].copy()
            return image
    image[y0:y1, x0:x1] = cv2.blur(image, (31, 31))[y0:y1, x0:x1]  # a box as large as the frame: no patch beside
    return image


def write_covered(sequence: Sequence, frames: range, out: Path) -> Path:
    """``out/NAME``: the video with ``frames`` covered, gt NaN there, ``cover.txt`` naming them."""
    assert sequence.video is not None, "the aerial-tracking layout (video.mp4 + gt.txt)"
    partial = out / f"{sequence.name}.partial"
    shutil.rmtree(partial, ignore_errors=True)
    partial.mkdir(parents=True)
    capture = cv2.VideoCapture(str(sequence.video))
    size = (int(capture.get(cv2.CAP_PROP_FRAME_WIDTH)), int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT)))
    capture.release()
    writer = cv2.VideoWriter(str(partial / VIDEO_NAME), cv2.VideoWriter.fourcc(*"mp4v"), sequence.fps, size)
    try:
        for index, image in enumerate(sequence.frames()):
            box = sequence.gt[index]
            writer.write(cover(image, box) if index in frames and not np.isnan(box).any() else image)
    finally:
        writer.release()
    lines = sequence.gt_path.read_text().splitlines()
    rows = [line for line in lines if line.strip()]
    for index in frames:
        rows[index] = "NaN,NaN,NaN,NaN"
    (partial / VIDEO_GT).write_text("".join(f"{row}\n" for row in rows))
    (partial / "cover.txt").write_text(f"covered frames {frames.start}..{frames.stop - 1} (counted from 0), "
                                       f"{len(frames)} frames = {len(frames) / sequence.fps:g} s at "
                                       f"{sequence.fps:g} fps; from {sequence.video}\n")
    shutil.rmtree(out / sequence.name, ignore_errors=True)
    partial.rename(out / sequence.name)
    return out / sequence.name


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", type=Path, help="the covered set's folder (written; not the set itself)")
    parser.add_argument("--set", type=Path, help="the aerial-tracking set (default: where the tests find it)")
    parser.add_argument("--seconds", type=float, default=2.0, help="length of the covered stretch (default 2)")
    parser.add_argument("--at", type=float, default=0.4, help="where it starts, share of the sequence (default 0.4)")
    parser.add_argument("--only", nargs="+", metavar="FOLDER", help="these sequences only")
    args = parser.parse_args(argv)
    source = args.set or aerial_tracking_set()
    if args.out.resolve() == source.resolve():
        parser.error("OUT is the set itself: give another folder")
    sequences = [s for s in find_sequences([source]) if not args.only or s.name in args.only]
    written, skipped = [], []
    for sequence in sequences:
        frames = stretch(sequence, args.seconds, args.at)
        if frames is None:
            skipped.append(f"{sequence.name} ({len(sequence)} frames at {sequence.fps:g} fps)")
            continue
        written.append(write_covered(sequence, frames, args.out))
        print(f"wrote {written[-1]}: frames {frames.start}..{frames.stop - 1} covered", flush=True)
    if skipped:
        print(f"left out, too short for 1 s + {args.seconds:g} s + 1 s: {', '.join(skipped)}")
    print(f"{args.out}: {len(written)} sequences")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
