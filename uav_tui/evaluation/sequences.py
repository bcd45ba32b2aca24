"""Annotated sequences on disk: finding them, reading their ground truth, decoding their frames one by one.

Two layouts are read:

* the ``aerial-tracking`` one: ``SEQ/video.mp4`` + ``SEQ/gt.txt``;
* OTB / UAV123: ``SEQ/img/*.jpg`` + ``SEQ/groundtruth_rect.txt``, or the images in ``SEQ/`` (or
  ``SEQ/img/``) with ``SEQ.txt`` beside the folder.

Ground truth is one ``x,y,w,h`` line per frame (commas, tabs or spaces), (x, y) the top-left corner in
pixels; ``NaN`` (or a zero-size box) marks a frame where the target is not visible. Frame 0 must have a box,
and it must overlap the frame (the tracker starts from it).

A sequence's frames are ``fps`` apart in its own time: the video's frame rate, or
:data:`IMAGE_SEQUENCE_FPS` for images (OTB's and UAV123's rate; UAV123@10fps is sampled from it).
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from processors.detection import DATA_DIR_ENV, find_data_dir
from uav_tui.errors import ConfigError, UavError

VIDEO_NAME, VIDEO_GT = "video.mp4", "gt.txt"
OTB_IMAGES, OTB_GT = "img", "groundtruth_rect.txt"
IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".bmp")
IMAGE_SEQUENCE_FPS = 30.0


class SequenceError(UavError):
    """An annotated sequence that cannot be read; the message names the file and what is wrong."""


@dataclass(frozen=True)
class Sequence:
    """One annotated sequence: where its frames are and the ground-truth box of every frame.

    Small and picklable (paths and a few numbers): jobs carry it to other processes and machines.
    """

    name: str
    gt_path: Path
    gt: np.ndarray
    """``N x 4`` float array ``x, y, w, h`` per frame; a row of NaN where the target is not visible."""
    video: Path | None = None
    images: tuple[Path, ...] = ()
    fps: float = IMAGE_SEQUENCE_FPS
    """Frames per second of the sequence's own time (what ``tmMgr.snapshot().frame_t_ns`` counts in)."""

    def __len__(self) -> int:
        return len(self.gt)

    @property
    def source(self) -> Path:
        """The file the frames come from (the video, or the first image)."""
        return self.video if self.video is not None else self.images[0]

    def frames(self) -> Iterator[np.ndarray]:
        """Decode the frames one at a time (BGR uint8); at most one is held.

        Raises:
            SequenceError: a frame cannot be decoded, or there are fewer frames than gt rows.
        """
        if self.video is not None:
            yield from self._video_frames(self.video)
            return
        for path in self.images:
            image = cv2.imread(str(path), cv2.IMREAD_COLOR)
            if image is None:
                raise SequenceError(f"{path}: cannot be read as an image")
            yield image

    def _video_frames(self, path: Path) -> Iterator[np.ndarray]:
        capture = cv2.VideoCapture(str(path))
        try:
            for index in range(len(self.gt)):
                ok, image = capture.read()
                if not ok:
                    raise SequenceError(f"{path}: ends after {index} frames but {self.gt_path} has {len(self.gt)} "
                                        "rows; give one gt row per frame")
                yield image
        finally:
            capture.release()


def find_sequences(paths: list[Path]) -> list[Sequence]:
    """Every sequence named by ``paths``: each is a sequence folder or a folder of them (sorted by name).

    Raises:
        SequenceError: a path does not exist, holds no sequence, or a sequence in it is broken.
    """
    found: list[Sequence] = []
    for path in paths:
        if not path.exists():
            raise SequenceError(f"{path} does not exist")
        if not path.is_dir():
            hint = f": name the folder it is in, {path.parent}" if _is_sequence(path.parent) else ""
            raise SequenceError(f"{path} is a file, not a sequence folder or a folder of them{hint}")
        if _is_sequence(path):
            found.append(load_sequence(path))
            continue
        children = [child for child in sorted(path.iterdir()) if child.is_dir() and _is_sequence(child)]
        if not children:
            raise SequenceError(f"{path} is not a sequence ({VIDEO_NAME} + {VIDEO_GT}, or {OTB_IMAGES}/*.jpg + "
                                f"{OTB_GT}) and holds none")
        found.extend(load_sequence(child) for child in children)
    return found


def load_sequence(folder: Path) -> Sequence:
    """Read one sequence folder in either layout (see the module docstring)."""
    video = folder / VIDEO_NAME
    if video.is_file():
        gt_path = folder / VIDEO_GT
        if not gt_path.is_file():
            raise SequenceError(f"{gt_path} is missing: a sequence needs one gt row per frame of {video}")
        gt = read_ground_truth(gt_path)
        capture = cv2.VideoCapture(str(video))
        frames = int(capture.get(cv2.CAP_PROP_FRAME_COUNT))
        size = (int(capture.get(cv2.CAP_PROP_FRAME_WIDTH)), int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT)))
        fps = capture.get(cv2.CAP_PROP_FPS)
        capture.release()
        _check_count(gt_path, gt, frames, video)
        _check_first_box(gt_path, gt, size)
        return Sequence(folder.name, gt_path, gt, video=video,
                        fps=fps if math.isfinite(fps) and fps > 0 else IMAGE_SEQUENCE_FPS)
    image_dir = folder / OTB_IMAGES if (folder / OTB_IMAGES).is_dir() else folder
    images = tuple(sorted(p for p in image_dir.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES))
    if not images:
        raise SequenceError(f"{folder}: no {VIDEO_NAME} and no images in {image_dir}")
    candidates = [folder / OTB_GT, folder.parent / f"{folder.name}.txt"]
    gt_path = next((p for p in candidates if p.is_file()), candidates[0])
    if not gt_path.is_file():
        raise SequenceError(f"{candidates[0]} is missing (nor is there {candidates[1]}): a sequence needs one gt "
                            "row per image")
    gt = read_ground_truth(gt_path)
    _check_count(gt_path, gt, len(images), image_dir)
    first = cv2.imread(str(images[0]), cv2.IMREAD_UNCHANGED)
    if first is None:
        raise SequenceError(f"{images[0]}: cannot be read as an image")
    _check_first_box(gt_path, gt, (first.shape[1], first.shape[0]))
    return Sequence(folder.name, gt_path, gt, images=images)


def read_ground_truth(path: Path) -> np.ndarray:
    """``N x 4`` boxes from a gt file; NaN rows (or zero-size boxes) where the target is not visible."""
    rows = []
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        if not line.strip():
            continue
        fields = [f for f in re.split(r"[,\s]+", line.strip()) if f]
        try:
            values = [float(f) for f in fields]
        except ValueError:
            values = []
        if len(values) != 4:
            raise SequenceError(f"{path}:{number}: expected x,y,w,h (4 numbers or NaN), got {line.strip()[:80]!r}")
        if not all(math.isfinite(v) for v in values) or values[2] <= 0 or values[3] <= 0:
            values = [math.nan] * 4
        rows.append(values)
    gt = np.array(rows, dtype=np.float64).reshape(-1, 4)
    if not len(gt) or np.isnan(gt[0]).any():
        raise SequenceError(f"{path}: the first row must be the target's box (the tracker starts from it)")
    return gt


def _check_count(gt_path: Path, gt: np.ndarray, frames: int, source: Path) -> None:
    if frames != len(gt):
        raise SequenceError(f"{gt_path} has {len(gt)} rows but {source} has {frames} frames; give one gt row "
                            "per frame")


def _check_first_box(gt_path: Path, gt: np.ndarray, size: tuple[int, int]) -> None:
    """The first box must overlap the frame: a tracker cannot start from a box outside it."""
    x, y, w, h = gt[0]
    width, height = size
    if width > 0 and height > 0 and not (x < width and y < height and x + w > 0 and y + h > 0):
        raise SequenceError(f"{gt_path}:1: the first box ({x:g}, {y:g}, {w:g}, {h:g}) is outside the {width}x{height} "
                            "frame; the tracker starts from it: give the target's box in frame 1's pixels (x, y of "
                            "its top-left corner, then width, height)")


def _is_sequence(folder: Path) -> bool:
    if (folder / VIDEO_NAME).is_file() or (folder / OTB_GT).is_file() or (folder / OTB_IMAGES).is_dir():
        return True
    image_dir = folder / OTB_IMAGES if (folder / OTB_IMAGES).is_dir() else folder
    sibling_gt = folder.parent / f"{folder.name}.txt"
    return sibling_gt.is_file() and any(p.suffix.lower() in IMAGE_SUFFIXES for p in image_dir.iterdir())


def aerial_tracking_set() -> Path:
    """The aerial-tracking set, where the tests find it; ConfigError saying how to get it when it is not here."""
    return shared_set("aerial-tracking", "scripts/build_tracking_set.py", "docs/evaluation.md")


def shared_set(name: str, builder: str, manual: str) -> Path:
    """The folder ``name`` in the shared data folder (:func:`~processors.detection.find_data_dir`); ConfigError
    naming the ``builder`` script and the ``manual`` page when it is not here."""
    try:
        folder = find_data_dir() / name
    except FileNotFoundError as exc:
        missing = str(exc)
    else:
        if folder.is_dir():
            return folder
        missing = f"{folder} is not here"
    raise ConfigError(f"no sequence folder given and the {name} set is not here ({missing}): give a folder, set "
                      f"{DATA_DIR_ENV} to the one holding {name}/, or build the set with {builder} ({manual})",
                      key="data")
