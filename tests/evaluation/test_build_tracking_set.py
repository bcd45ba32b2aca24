"""``scripts/build_tracking_set.py``, offline: its source list, a sequence written from a local repository (fetched
with git from a ``file://`` one made here, so the real fetch steps run without a network), and its errors."""

from __future__ import annotations

import dataclasses
import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import cv2
import numpy as np
import pytest

from tests.evaluation.conftest import BOXES, SIZE, frames
from tests.scripts import script_module
from uav_tui.evaluation import load_sequence

COMMIT = "0" * 40
BLOCK = f"""folder: uav123_10fps-box1
dataset: UAV123@10fps
sequence: box1
frames: 5 (96x64), video written at 10 fps (mp4v); gt line i = video frame i
repository: https://github.com/someone/Some-Tracker commit {COMMIT}
images: data_seq/box1/img0002.jpg .. img0006.jpg
ground truth: anno/box1.txt (6 rows, x,y,w,h; first 5 used)
licence: none stated in the repository
"""
"""A list block for images 2-6 of the generated sequence, whose annotation (one row a frame from image 2, and one
more) is cut to the first 5 rows."""


@pytest.fixture(scope="module")
def builder() -> Iterator[ModuleType]:
    with script_module("build_tracking_set") as module:
        yield module


def git(folder: Path, *args: str) -> str:
    return subprocess.run(["git", "-C", str(folder), "-c", "user.name=t", "-c", "user.email=t@t", *args],
                          capture_output=True, text=True, check=True).stdout.strip()


@pytest.fixture
def upstream(tmp_path: Path) -> Path:
    """A git repository laid out as the benchmark repositories are: the generated images, a tab-separated gt from
    image 2 on with a NaN row and a fractional value, and a file the sequence does not use."""
    if shutil.which("git") is None:
        pytest.skip("git is not installed")
    repo = tmp_path / "upstream"
    (repo / "data_seq" / "box1").mkdir(parents=True)
    (repo / "anno").mkdir()
    for number, image in enumerate(frames(), start=1):
        cv2.imwrite(str(repo / "data_seq" / "box1" / f"img{number:04d}.jpg"), image)
    rows = ["\t".join("NaN" if np.isnan(v) else f"{v:g}" for v in box) for box in [*BOXES[1:], [34, 20, 20, 16]]]
    rows[0] = rows[0].replace("14", "14.5", 1)
    (repo / "anno" / "box1.txt").write_text("\n".join(rows) + "\n")
    (repo / "unused.bin").write_bytes(b"x" * 1000)
    git(repo, "init", "-q")
    git(repo, "add", ".")
    git(repo, "commit", "-q", "-m", "sequences")
    return repo


def test_the_list_names_the_nineteen_sequences_of_the_set(builder: ModuleType) -> None:
    sequences = builder.read_list()
    assert len(sequences) == 19 and len({s.folder for s in sequences}) == 19
    assert {s.repository.split("/")[3] for s in sequences} == {"vision4robotics"}
    by_name = {s.folder: s for s in sequences}
    group = by_name["uav123_10fps-group2_2"]  # a sub-sequence: images 303-482 of group2
    assert group.images[0] == "UAV123_10fps/data_seq/group2/000303.jpg" and len(group.images) == group.frames == 180
    assert group.gt == "UAV123_10fps/anno/group2_2.txt"
    bus = by_name["uavdt-S0310"]  # images named img000001.jpg
    assert bus.images[-1] == "seq/S0310/img000118.jpg" and bus.size == (1024, 540) and bus.fps == 30
    assert bus.checkout == "MSCF-tracker@4411a16e9e92d1989ae6e8789b3a75e9d5579749"


def test_the_list_is_the_one_the_set_here_was_built_from(builder: ModuleType, aerial_tracking: Path) -> None:
    sequences = builder.read_list()
    assert sorted(s.folder for s in sequences) == sorted(p.name for p in aerial_tracking.iterdir() if p.is_dir())
    for sequence in sequences:
        folder = aerial_tracking / sequence.folder
        assert (folder / "source.txt").read_text() == sequence.source_text, sequence.folder
        assert len((folder / "gt.txt").read_text().splitlines()) == sequence.frames, sequence.folder


def test_a_sequence_is_fetched_and_written_in_the_set_s_layout(builder: ModuleType, upstream: Path,
                                                               tmp_path: Path) -> None:
    listed = builder.parse_sequence(BLOCK)
    sequence = dataclasses.replace(listed, repository=upstream.as_uri(), commit=git(upstream, "rev-parse", "HEAD"))
    out, sources = tmp_path / "set", tmp_path / "sources"
    (out / f"{sequence.folder}.partial").mkdir(parents=True)  # an interrupted build's leftover
    assert builder.build([sequence], out, sources, offline=False) == [out / sequence.folder]

    checkout = sources / f"upstream@{sequence.commit}"
    assert not (checkout / "unused.bin").exists()  # only the files the sequence uses are checked out
    assert sorted(p.name for p in out.iterdir()) == [sequence.folder]
    written = out / sequence.folder
    assert (written / "source.txt").read_text() == BLOCK.removeprefix("folder: uav123_10fps-box1\n")
    assert (written / "gt.txt").read_text().splitlines() == ["14.5,12,20,16", "NaN,NaN,NaN,NaN", "22,14,20,16",
                                                              "26,16,20,16", "30,18,20,16"]
    loaded = load_sequence(written)  # as uav-tui eval and the tests read it
    assert loaded.fps == 10 and len(loaded.gt) == 5
    video = list(loaded.frames())
    assert len(video) == 5 and video[0].shape == (SIZE[1], SIZE[0], 3)
    assert np.abs(video[2].astype(int) - frames()[3]).mean() < 6  # image 4, through JPEG and MPEG-4

    shutil.rmtree(checkout)
    assert builder.build([sequence], out, sources, offline=True) == []  # done already: nothing fetched or written


def test_what_cannot_be_built_says_what_to_do_and_leaves_no_sequence(builder: ModuleType, upstream: Path,
                                                                     tmp_path: Path) -> None:
    sequence = builder.parse_sequence(BLOCK)
    with pytest.raises(builder.BuildError, match=r"no copy of https://github.com/someone/Some-Tracker @ 0+ in .*"
                                                 r"run without --offline on a machine with internet access"):
        builder.build([sequence], tmp_path / "set", tmp_path / "sources", offline=True)

    (upstream / "data_seq" / "box1" / "img0004.jpg").unlink()
    (tmp_path / "sources").mkdir()
    upstream.rename(tmp_path / "sources" / sequence.checkout)  # the local copy the block names
    with pytest.raises(builder.BuildError, match=r"img0004.jpg is missing or not an image"):
        builder.build([sequence], tmp_path / "set", tmp_path / "sources", offline=True)
    assert not (tmp_path / "set" / sequence.folder).exists()

    with pytest.raises(builder.BuildError, match=r"box1: images 2\.\.6 are 5, not 4 frames"):
        builder.parse_sequence(BLOCK.replace("frames: 5", "frames: 4"))
    with pytest.raises(builder.BuildError, match=r"box1: 'repository: .*' does not read as"):
        builder.parse_sequence(BLOCK.replace(f"commit {COMMIT}", "commit main"))
    with pytest.raises(builder.BuildError, match="a path leaves the repository"):
        builder.parse_sequence(BLOCK.replace("anno/box1.txt", "../../etc/box1.txt"))


def test_the_command_says_what_is_missing(builder: ModuleType, tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    assert builder.main([str(tmp_path / "set"), "--only", "dtb70-Gull3"]) == 1
    assert "--only dtb70-Gull3: not in tracking_set.txt" in capsys.readouterr().err
    assert builder.main([str(tmp_path / "set"), "--only", "dtb70-Gull2", "--offline"]) == 1
    said = capsys.readouterr().err
    commit = "4411a16e9e92d1989ae6e8789b3a75e9d5579749"
    assert f"no copy of https://github.com/vision4robotics/MSCF-tracker @ {commit} in " \
           f"{tmp_path / 'set-sources' / f'MSCF-tracker@{commit}'}" in said
    assert not (tmp_path / "set").exists()
