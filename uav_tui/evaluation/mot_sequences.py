"""Multi-object sequences on disk, in the MOTChallenge layout, and which of their objects are scored.

A sequence folder holds ``img1/*.jpg`` (the frames, in name order), ``gt/gt.txt`` and ``seqinfo.ini``
(``frameRate``); ``source.txt`` says where it comes from. ``gt.txt`` has one object a line,
``frame, id, x, y, w, h, conf, class, visibility`` (frame from 1, (x, y) the top-left corner in pixels).
``class`` is the VisDrone category (``scripts/build_mot_set.py`` keeps it as the benchmark wrote it); ``conf`` 0
marks a box the benchmark itself does not score.

What is scored (:data:`SCORED`): the objects of the VisDrone categories that the shipped Yolo-Fastest (COCO classes)
has a class for, all as one class (a van the detector calls a truck is still found): pedestrian and people
(``person``), bicycle, car and van (``car``), truck, bus, motor (``motorbike``). The detector's other classes are not
scored; the VisDrone boxes it has no class for (tricycles, ``others``), those with ``conf`` 0 and the ignored regions
are *ignored*: a reported box that covers one of them by IoU 0.5 or more is dropped before scoring (as MOTChallenge
drops the boxes matched to its distractors), neither a hit nor a false positive.
"""

from __future__ import annotations

import configparser
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from uav_tui.evaluation.sequences import IMAGE_SUFFIXES, SequenceError, shared_set

MOT_SET = "aerial-mot"
"""The multi-object set's folder in the data folder (beside ``aerial-tracking``)."""
FRAMES, GT, INFO = "img1", "gt/gt.txt", "seqinfo.ini"

SCORED = {1: "person", 2: "person", 3: "bicycle", 4: "car", 5: "car", 6: "truck", 9: "bus", 10: "motorbike"}
"""VisDrone category -> the Yolo-Fastest (COCO) class that finds it; the scored objects."""
SCORED_LABELS = frozenset(SCORED.values())
"""The detector's classes whose boxes are scored."""


@dataclass(frozen=True)
class MotSequence:
    """One multi-object sequence: its frames and every ground-truth box (picklable: jobs carry it to workers)."""

    name: str
    images: tuple[Path, ...]
    gt: np.ndarray
    """``N x 9`` rows ``frame, id, x, y, w, h, conf, class, visibility`` as in ``gt.txt``."""
    fps: float

    def __len__(self) -> int:
        return len(self.images)

    def scored(self, frame: int) -> tuple[np.ndarray, np.ndarray]:
        """Frame ``frame`` (1 = the first)'s scored objects: their ids and ``x, y, w, h`` boxes."""
        rows = self.gt[(self.gt[:, 0] == frame) & self._is_scored()]
        return rows[:, 1].astype(np.int64), rows[:, 2:6]

    def ignored(self, frame: int) -> np.ndarray:
        """Frame ``frame``'s ignored boxes (``x, y, w, h``): what a report may cover without being counted."""
        return self.gt[(self.gt[:, 0] == frame) & ~self._is_scored()][:, 2:6]

    def _is_scored(self) -> np.ndarray:
        return (self.gt[:, 6] != 0) & np.isin(self.gt[:, 7], list(SCORED))


def load_mot_sequence(folder: Path) -> MotSequence:
    """Read one sequence folder (see the module docstring).

    Raises:
        SequenceError: naming the file and what is wrong with it.
    """
    image_dir, gt_path, info_path = folder / FRAMES, folder / GT, folder / INFO
    for needed in (image_dir, gt_path, info_path):
        if not needed.exists():
            raise SequenceError(f"{needed} is missing: a multi-object sequence has {FRAMES}/, {GT} and {INFO}")
    images = tuple(sorted(p for p in image_dir.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES))
    if not images:
        raise SequenceError(f"{image_dir} holds no images")
    info = configparser.ConfigParser()
    info.read(info_path)
    try:
        fps = float(info["Sequence"]["frameRate"])
    except (KeyError, ValueError):
        raise SequenceError(f"{info_path}: no [Sequence] frameRate") from None
    gt = read_mot_gt(gt_path)
    if len(gt) and (gt[:, 0].min() < 1 or gt[:, 0].max() > len(images)):
        raise SequenceError(f"{gt_path}: frames {int(gt[:, 0].min())}..{int(gt[:, 0].max())}, but {image_dir} has "
                            f"{len(images)} images (frames are counted from 1)")
    return MotSequence(folder.name, images, gt, fps)


def read_mot_gt(path: Path) -> np.ndarray:
    """``N x 9`` rows of a MOTChallenge ``gt.txt``; a line with other than 9 numbers is an error naming it."""
    rows = []
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        if not line.strip():
            continue
        try:
            values = [float(f) for f in re.split(r"[,\s]+", line.strip()) if f]
        except ValueError:
            values = []
        if len(values) != 9:
            raise SequenceError(f"{path}:{number}: expected frame,id,x,y,w,h,conf,class,visibility, got "
                                f"{line.strip()[:80]!r}")
        rows.append(values)
    return np.array(rows, np.float64).reshape(-1, 9)


def find_mot_sequences(paths: list[Path]) -> list[MotSequence]:
    """Every sequence named by ``paths``: each a sequence folder or a folder of them (sorted by name)."""
    found: list[MotSequence] = []
    for path in paths:
        if not path.is_dir():
            raise SequenceError(f"{path} is not a folder")
        if (path / GT).is_file():
            found.append(load_mot_sequence(path))
            continue
        children = [child for child in sorted(path.iterdir()) if (child / GT).is_file()]
        if not children:
            raise SequenceError(f"{path} is not a multi-object sequence ({FRAMES}/, {GT}, {INFO}) and holds none")
        found.extend(load_mot_sequence(child) for child in children)
    return found


def aerial_mot_set() -> Path:
    """The multi-object set where the tests find it; ConfigError saying how to build it when it is not here."""
    return shared_set(MOT_SET, "scripts/build_mot_set.py", "docs/evaluation.md#the-multi-object-set")
