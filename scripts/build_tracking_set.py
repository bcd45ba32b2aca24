"""Build the aerial-tracking set (``video.mp4`` + ``gt.txt`` + ``source.txt`` a sequence) from its public sources.

    .venv/bin/python scripts/build_tracking_set.py [OUT] [--sources DIR] [--offline] [--only FOLDER ...]

Needs internet access and ``git``, once: each repository that ``scripts/tracking_set.txt`` names is fetched at its
commit, only the images and ground-truth files used (a sparse, blob-less fetch), into ``--sources`` (default
``OUT-sources``, kept, so that a second run needs no network; delete it when done). Then each sequence's images are
written as ``video.mp4`` (OpenCV, ``mp4v``, at the sequence's fps), the first rows of its ground truth as
``gt.txt`` (commas between the values, the values as written there) and its block of the list as ``source.txt``.
A sequence is written into a ``.partial`` folder and renamed when complete: an interrupted build goes on where it
stopped. OUT defaults to ``$UAV_TUI_DATA_DIR/aerial-tracking``, else ``shared/data/aerial-tracking`` beside the
repository: where the tests and ``uav-tui eval`` look for it. ``--offline`` uses only the copies in ``--sources``.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

import cv2

ROOT = Path(__file__).resolve().parents[1]
LIST = ROOT / "scripts" / "tracking_set.txt"
DATA_DIR_ENV = "UAV_TUI_DATA_DIR"  # as processors.detection names it; not imported: this script needs only cv2
FETCH_TIMEOUT_S = 3600


class BuildError(Exception):
    """A source list, a local copy or a fetch that cannot give the set; the message says which and what to do."""


@dataclass(frozen=True)
class Sequence:
    """One sequence of the list: where its images and ground truth are, and what to write."""

    folder: str
    source_text: str
    repository: str
    commit: str
    images: tuple[str, ...]
    gt: str
    frames: int
    size: tuple[int, int]
    fps: float

    @property
    def checkout(self) -> str:
        """The local copy's folder name under ``--sources``."""
        return f"{self.repository.rstrip('/').rsplit('/', 1)[-1]}@{self.commit}"


def _field(block: dict[str, str], key: str, pattern: str, folder: str) -> re.Match[str]:
    match = re.fullmatch(pattern, block.get(key, ""))
    if match is None:
        raise BuildError(f"{LIST.name}, {folder}: '{key}: {block.get(key, '')}' does not read as {pattern}")
    return match


def parse_sequence(text: str) -> Sequence:
    """One block of the list: ``folder: NAME``, then the ``key: value`` lines of that sequence's ``source.txt``."""
    lines = text.strip("\n").splitlines()
    block = dict(line.split(": ", 1) for line in lines if ": " in line)
    folder = block.get("folder", "")
    if not re.fullmatch(r"[\w.-]+", folder) or folder.startswith("."):
        raise BuildError(f"{LIST.name}: a block starts '{lines[0] if lines else ''}', not 'folder: NAME'")
    frames = _field(block, "frames", r"(\d+) \((\d+)x(\d+)\), video written at (\d+(?:\.\d+)?) fps.*", folder)
    repository = _field(block, "repository", r"(https://github\.com/[\w.-]+/[\w.-]+) commit ([0-9a-f]{40})", folder)
    images = _field(block, "images", r"(\S+/)(\D*)(\d+)(\.\w+) \.\. \2(\d+)\4", folder)
    gt = _field(block, "ground truth", r"(\S+) \(.*", folder).group(1)
    start, end, width = int(images.group(3)), int(images.group(5)), len(images.group(3))
    count = int(frames.group(1))
    if end - start + 1 != count:
        raise BuildError(f"{LIST.name}, {folder}: images {start}..{end} are {end - start + 1}, not {count} frames")
    paths = (images.group(1), gt, *(f"{images.group(1)}{images.group(2)}{n:0{width}d}{images.group(4)}"
                                    for n in range(start, end + 1)))
    if any(PurePosixPath(path).is_absolute() or ".." in PurePosixPath(path).parts for path in paths):
        raise BuildError(f"{LIST.name}, {folder}: a path leaves the repository")
    source_text = "".join(f"{line}\n" for line in lines if not line.startswith("folder: "))
    return Sequence(folder, source_text, repository.group(1), repository.group(2), paths[2:], gt, count,
                    (int(frames.group(2)), int(frames.group(3))), float(frames.group(4)))


def read_list(path: Path = LIST) -> list[Sequence]:
    """Every sequence of the list (blocks apart by blank lines; ``#`` lines are comments)."""
    text = "\n".join(line for line in path.read_text().splitlines() if not line.startswith("#"))
    sequences = [parse_sequence(block) for block in re.split(r"\n\s*\n", text) if block.strip()]
    folders = [s.folder for s in sequences]
    if len(set(folders)) != len(folders):
        raise BuildError(f"{path.name}: a folder is named twice")
    return sequences


def fetch(repository: str, commit: str, paths: list[str], into: Path) -> None:
    """Only ``paths`` of ``repository`` at ``commit``, checked out into ``into`` (git: sparse, blob-less, depth 1)."""
    partial = into.with_name(into.name + ".partial")
    shutil.rmtree(partial, ignore_errors=True)
    partial.mkdir(parents=True)
    git = ["git", "-C", str(partial), "-c", "advice.detachedHead=false"]
    patterns = "".join(f"/{path}\n" for path in paths)  # anchored: these files only
    steps = [(git + ["init", "-q"], None), (git + ["sparse-checkout", "set", "--no-cone", "--stdin"], patterns),
             (git + ["fetch", "-q", "--depth", "1", "--filter=blob:none", repository, commit], None),
             (git + ["checkout", "-q", "FETCH_HEAD"], None)]
    for command, stdin in steps:
        try:
            subprocess.run(command, input=stdin, text=True, check=True, capture_output=True, timeout=FETCH_TIMEOUT_S)
        except FileNotFoundError as exc:
            raise BuildError("git is not installed: install it (apt install git), or give --sources a folder "
                             "holding the copies") from exc
        except (subprocess.CalledProcessError, subprocess.TimeoutExpired) as exc:
            said = (getattr(exc, "stderr", None) or "").strip().splitlines()[-1:] or ["timed out"]
            raise BuildError(f"git {command[len(git)]} of {repository} @ {commit} failed ({said[0]}): check the "
                             "network and run again (what is done is kept)") from exc
    partial.rename(into)


def write_sequence(sequence: Sequence, checkout: Path, out: Path) -> Path:
    """``out/FOLDER`` from the local copy of its repository: video.mp4, gt.txt, source.txt."""
    rows = []
    gt_path = checkout / sequence.gt
    if not gt_path.is_file():
        raise BuildError(f"{sequence.folder}: {gt_path} is missing: delete {checkout} and run again to fetch it")
    for number, line in enumerate(gt_path.read_text().splitlines()[:sequence.frames], start=1):
        values = [v for v in re.split(r"[,\s]+", line.strip()) if v]
        if len(values) != 4:
            raise BuildError(f"{gt_path}:{number}: '{line[:60]}' is not x,y,w,h")
        rows.append(",".join(values) + "\n")
    if len(rows) < sequence.frames:
        raise BuildError(f"{gt_path} has {len(rows)} rows, the sequence {sequence.frames} frames")
    partial = out / f"{sequence.folder}.partial"
    shutil.rmtree(partial, ignore_errors=True)
    partial.mkdir(parents=True)
    writer = cv2.VideoWriter(str(partial / "video.mp4"), cv2.VideoWriter.fourcc(*"mp4v"), sequence.fps, sequence.size)
    try:
        for image_path in sequence.images:
            image = cv2.imread(str(checkout / image_path))
            if image is None:
                raise BuildError(f"{sequence.folder}: {checkout / image_path} is missing or not an image")
            if (image.shape[1], image.shape[0]) != sequence.size:
                raise BuildError(f"{checkout / image_path} is {image.shape[1]}x{image.shape[0]}, the list says "
                                 f"{sequence.size[0]}x{sequence.size[1]}")
            writer.write(image)
    finally:
        writer.release()
    (partial / "gt.txt").write_text("".join(rows))
    (partial / "source.txt").write_text(sequence.source_text)
    shutil.rmtree(out / sequence.folder, ignore_errors=True)
    partial.rename(out / sequence.folder)
    return out / sequence.folder


def build(sequences: list[Sequence], out: Path, sources: Path, *, offline: bool) -> list[Path]:
    """Every sequence not yet in ``out``; fetches the copies ``sources`` lacks unless ``offline``."""
    written = []
    for sequence in sequences:
        if (out / sequence.folder / "source.txt").is_file():
            continue
        checkout = sources / sequence.checkout
        if not checkout.is_dir():
            if offline:
                raise BuildError(f"{sequence.folder}: no copy of {sequence.repository} @ {sequence.commit} in "
                                 f"{checkout}: run without --offline on a machine with internet access")
            needed = [p for s in sequences if s.checkout == sequence.checkout for p in (s.gt, *s.images)]
            print(f"fetching {sequence.repository} @ {sequence.commit[:7]} ({len(needed)} files)", flush=True)
            fetch(sequence.repository, sequence.commit, needed, checkout)
        written.append(write_sequence(sequence, checkout, out))
        print(f"wrote {written[-1]}", flush=True)
    return written


def default_out() -> Path:
    env = os.environ.get(DATA_DIR_ENV)
    return (Path(env) if env else ROOT.parent / "shared" / "data") / "aerial-tracking"


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", nargs="?", type=Path, default=default_out(),
                        help="the set's folder (default: %(default)s)")
    parser.add_argument("--sources", type=Path, help="the repositories' local copies (default: OUT-sources)")
    parser.add_argument("--offline", action="store_true", help="fetch nothing: use the copies in --sources only")
    parser.add_argument("--only", nargs="+", metavar="FOLDER", help="these sequences only")
    args = parser.parse_args(argv)
    try:
        sequences = read_list()
        unknown = set(args.only or ()) - {s.folder for s in sequences}
        if unknown:
            raise BuildError(f"--only {' '.join(sorted(unknown))}: not in {LIST.name}")
        chosen = [s for s in sequences if not args.only or s.folder in args.only]
        written = build(chosen, args.out, args.sources or args.out.with_name(args.out.name + "-sources"),
                        offline=args.offline)
    except BuildError as exc:
        print(f"build_tracking_set: {exc}", file=sys.stderr)
        return 1
    print(f"{args.out}: {len(chosen)} sequences ({len(written)} written now); tests and uav-tui eval find it "
          f"{'there' if args.out == default_out() else f'with {DATA_DIR_ENV}={args.out.parent}'}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
