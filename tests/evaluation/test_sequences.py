"""Both layouts load; broken sequences say which file is wrong."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.evaluation.conftest import BOXES, write_gt, write_image_sequence, write_video_sequence
from uav_tui.evaluation import SequenceError, find_sequences


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return bool(np.array_equal(a, b, equal_nan=True))


def test_a_video_sequence_loads_and_decodes_every_frame(video_sequence: Path) -> None:
    [sequence] = find_sequences([video_sequence])
    assert sequence.name == "moving-box" and len(sequence) == 6 and _same(sequence.gt, BOXES)
    decoded = list(sequence.frames())
    assert len(decoded) == 6 and decoded[0].shape == (64, 96, 3)


@pytest.mark.parametrize("gt_beside", [False, True], ids=["groundtruth_rect", "seq.txt-beside"])
def test_an_otb_sequence_loads(tmp_path: Path, gt_beside: bool) -> None:
    folder = write_image_sequence(tmp_path / "seqs" / "Box1", gt_beside=gt_beside)
    [sequence] = find_sequences([folder])
    assert sequence.name == "Box1" and _same(sequence.gt, BOXES) and len(list(sequence.frames())) == 6


def test_a_folder_of_sequences_loads_all_of_them_by_name(tmp_path: Path) -> None:
    write_video_sequence(tmp_path / "b-video")
    write_image_sequence(tmp_path / "a-images")
    (tmp_path / "notes").mkdir()
    assert [s.name for s in find_sequences([tmp_path])] == ["a-images", "b-video"]


def test_missing_ground_truth_names_the_file(video_sequence: Path) -> None:
    (video_sequence / "gt.txt").unlink()
    with pytest.raises(SequenceError, match=f"{video_sequence / 'gt.txt'} is missing"):
        find_sequences([video_sequence])


def test_missing_otb_ground_truth_names_the_file(tmp_path: Path) -> None:
    folder = write_image_sequence(tmp_path / "Box1")
    (folder / "groundtruth_rect.txt").unlink()
    with pytest.raises(SequenceError, match="groundtruth_rect.txt is missing"):
        find_sequences([tmp_path])


def test_fewer_gt_rows_than_frames_names_both(video_sequence: Path) -> None:
    write_gt(video_sequence / "gt.txt", BOXES[:4])
    with pytest.raises(SequenceError, match=r"gt.txt has 4 rows but .*video.mp4 has 6 frames"):
        find_sequences([video_sequence])


def test_a_bad_line_names_the_file_and_line(video_sequence: Path) -> None:
    (video_sequence / "gt.txt").write_text("1,2,3,4\n1,2,three,4\n")
    with pytest.raises(SequenceError, match=r"gt.txt:2: expected x,y,w,h"):
        find_sequences([video_sequence])


def test_a_folder_without_sequences_says_what_one_is(tmp_path: Path) -> None:
    with pytest.raises(SequenceError, match="video.mp4 \\+ gt.txt"):
        find_sequences([tmp_path])


def test_a_file_is_not_a_sequence_and_its_folder_is_suggested(video_sequence: Path) -> None:
    with pytest.raises(SequenceError, match=f"video.mp4 is a file, .*: name the folder it is in, {video_sequence}$"):
        find_sequences([video_sequence / "video.mp4"])
    (video_sequence.parent / "notes.txt").write_text("")
    with pytest.raises(SequenceError, match="notes.txt is a file, not a sequence folder or a folder of them$"):
        find_sequences([video_sequence.parent / "notes.txt"])
