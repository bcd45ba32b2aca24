"""Build the multi-object set (``aerial-mot``) from the VisDrone2019-MOT validation set.

VisDrone publishes its data for academic, non-commercial use and not for redistribution, so the set is built on
each machine from the benchmark's own download (``VisDrone2019-MOT-val.zip`` from the VisDrone-Dataset page,
unpacked: ``annotations/<seq>.txt`` and ``sequences/<seq>/0000001.jpg ..``). For each sequence listed in
``scripts/mot_set.txt`` (its name, first frame, frame count) it writes ``OUT/<seq>/``:

* ``img1/000001.jpg ..``: the frames, copied;
* ``gt/gt.txt``: the annotation rows of those frames, renumbered from 1, as MOTChallenge lays them out
  (``frame, id, x, y, w, h, conf, class, visibility``): VisDrone's score becomes ``conf``, its category ``class``, and
  its occlusion (0 none, 1 partial, 2 heavy) ``visibility`` 1, 0.5, 0.25;
* ``seqinfo.ini`` (30 frames a second, VisDrone's rate) and ``source.txt`` (where it comes from).

Usage: python scripts/build_mot_set.py VisDrone2019-MOT-val [OUT]   (OUT: ../shared/data/aerial-mot)
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
LIST = ROOT / "scripts" / "mot_set.txt"
FPS = 30
VISIBILITY = {0: 1.0, 1: 0.5, 2: 0.25}
SOURCE = ("VisDrone2019-MOT validation set (Zhu et al., 'Detection and Tracking Meet Drones Challenge', TPAMI 2021), "
          "AISKYEYE team, Tianjin University; academic non-commercial use; sequence {seq}, frames {first}..{last} "
          "of sequences/{seq}/ and the matching rows of annotations/{seq}.txt")


def read_list(path: Path = LIST) -> list[tuple[str, int, int]]:
    """``(sequence, first frame, frames)`` of each non-comment line of the list."""
    entries = []
    for line in path.read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            seq, first, count = line.split()
            entries.append((seq, int(first), int(count)))
    return entries


def build_sequence(visdrone: Path, out: Path, seq: str, first: int, count: int) -> Path:
    """Write ``out/seq`` from the VisDrone folder (see the module docstring); a ``.partial`` folder until done."""
    images = sorted((visdrone / "sequences" / seq).glob("*.jpg"))[first - 1:first - 1 + count]
    if len(images) < count:
        raise SystemExit(f"{visdrone / 'sequences' / seq} has {len(images)} frames from {first}, {count} wanted")
    rows = np.loadtxt(visdrone / "annotations" / f"{seq}.txt", delimiter=",", ndmin=2)
    rows = rows[(rows[:, 0] >= first) & (rows[:, 0] < first + count)]
    target, partial = out / seq, out / f"{seq}.partial"
    shutil.rmtree(partial, ignore_errors=True)
    (partial / "img1").mkdir(parents=True)
    (partial / "gt").mkdir()
    for number, image in enumerate(images, start=1):
        shutil.copyfile(image, partial / "img1" / f"{number:06d}.jpg")
    lines = [f"{int(r[0]) - first + 1},{int(r[1])},{r[2]:g},{r[3]:g},{r[4]:g},{r[5]:g},{int(r[6])},{int(r[7])},"
             f"{VISIBILITY.get(int(r[9]), 1.0):g}" for r in rows]
    (partial / "gt" / "gt.txt").write_text("".join(f"{line}\n" for line in lines))
    (partial / "seqinfo.ini").write_text(f"[Sequence]\nname={seq}\nimDir=img1\nframeRate={FPS}\nseqLength={count}\n"
                                         "imExt=.jpg\n")
    (partial / "source.txt").write_text(SOURCE.format(seq=seq, first=first, last=first + count - 1) + "\n")
    shutil.rmtree(target, ignore_errors=True)
    partial.rename(target)
    return target


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("visdrone", type=Path, help="the unpacked VisDrone2019-MOT-val folder")
    parser.add_argument("out", type=Path, nargs="?", default=ROOT.parent / "shared" / "data" / "aerial-mot")
    args = parser.parse_args(argv)
    for seq, first, count in read_list():
        print(build_sequence(args.visdrone, args.out, seq, first, count))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
