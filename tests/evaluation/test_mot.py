"""``uav-tui eval --mot``: TrackEval's scores on hand-made tracks whose HOTA / IDF1 / MOTA are known, a job over a
generated sequence with a processor that reports the truth, the set's builder, and the real multi-object set."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import cv2
import numpy as np
import pytest

from processors.detection import DATA_DIR_ENV, find_data_dir
from tests.scripts import script_module
from tests.videos import WANT_OF_DATA
from uav_tui.evaluation import mot_cli
from uav_tui.evaluation.mot_metrics import combine, score_tracks
from uav_tui.evaluation.mot_runner import MotJob, run_mot_job
from uav_tui.evaluation.mot_sequences import MOT_SET, find_mot_sequences, load_mot_sequence

BOX = np.array([[10.0, 10.0, 20.0, 20.0]])
NONE = (np.zeros(0, np.int64), np.zeros((0, 4)))


def test_an_id_switch_halfway_halves_idf1_and_association() -> None:
    # one object on 4 frames, reported exactly, as track 7 on two frames then as track 8
    gt = [(np.array([1]), BOX)] * 4
    switched = score_tracks(gt, [(np.array([7]), BOX)] * 2 + [(np.array([8]), BOX)] * 2)
    assert switched.deta == pytest.approx(1.0)
    assert switched.assa == pytest.approx(0.5)  # each match shares its track with half of the object's frames
    assert switched.hota == pytest.approx(math.sqrt(0.5))
    assert switched.idf1 == pytest.approx(0.5)  # IDTP 2, IDFP 2, IDFN 2
    assert switched.mota == pytest.approx(0.75)  # one switch in 4 objects
    assert switched.id_switches == 1
    perfect = score_tracks(gt, [(np.array([3]), BOX)] * 4)
    assert (perfect.hota, perfect.idf1, perfect.mota) == pytest.approx((1.0, 1.0, 1.0))
    assert combine([switched, perfect]).idf1 == pytest.approx(0.75)  # 6 IDTP of 8 both ways
    nothing = score_tracks(gt, [NONE] * 4)
    assert (nothing.hota, nothing.idf1, nothing.mota) == (0.0, 0.0, 0.0)


def test_a_missed_frame_and_a_false_box_count_as_MOTChallenge_counts_them() -> None:
    gt = [(np.array([1]), BOX)] * 4
    far = np.array([[100.0, 100.0, 20.0, 20.0]])
    reported = [(np.array([5]), BOX), NONE, (np.array([5]), BOX), (np.array([5, 6]), np.vstack([BOX, far]))]
    scores = score_tracks(gt, reported)
    assert scores.mota == pytest.approx(1 - (1 + 1) / 4)  # one miss, one false positive
    assert scores.idf1 == pytest.approx(2 * 3 / (2 * 3 + 1 + 1))
    assert (scores.gt_boxes, scores.reported_boxes) == (4, 4)


TRUTH = '''
import numpy as np

class Truth:
    """Reports each frame's gt rows as detections (label by VisDrone class) and one cat: a perfect detector."""

    LABELS = {4: "car", 7: "tricycle"}

    def __init__(self, gt):
        self.rows, self.frame, self.detections = np.loadtxt(gt, delimiter=",", ndmin=2), 0, []

    def photo_processing(self, image):
        self.frame += 1
        rows = self.rows[self.rows[:, 0] == self.frame]
        self.detections = [((int(r[2]), int(r[3]), int(r[4]), int(r[5])), self.LABELS[int(r[7])], 0.9) for r in rows]
        self.detections.append(((0, 0, 8, 8), "cat", 0.9))
'''


def write_sequence(folder: Path, frames: int = 20) -> Path:
    """Two cars driving towards each other along a row, and a parked tricycle (not scored: the detector has no
    class for it), in the MOTChallenge layout."""
    (folder / "img1").mkdir(parents=True)
    (folder / "gt").mkdir()
    rows = []
    for frame in range(1, frames + 1):
        image = np.full((120, 200, 3), 60, np.uint8)
        for car, x in ((1, 10 + 6 * frame), (2, 170 - 6 * frame)):
            rows.append(f"{frame},{car},{x},{40 + 30 * (car - 1)},20,12,1,4,1")
            cv2.rectangle(image, (x, 40 + 30 * (car - 1)), (x + 20, 52 + 30 * (car - 1)), (0, 0, 200), -1)
        rows.append(f"{frame},3,90,100,16,10,1,7,1")
        cv2.imwrite(str(folder / "img1" / f"{frame:06d}.jpg"), image)
    (folder / "gt" / "gt.txt").write_text("\n".join(rows) + "\n")
    (folder / "seqinfo.ini").write_text("[Sequence]\nname=cars\nframeRate=10\n")
    return folder


def test_a_perfect_detector_s_tracks_score_full_marks_and_unscored_boxes_do_not_count(tmp_path: Path) -> None:
    folder = write_sequence(tmp_path / "mot" / "cars")
    (tmp_path / "truth.py").write_text(TRUTH)
    sequence = load_mot_sequence(folder)
    result = run_mot_job(MotJob(sequence, f"{tmp_path / 'truth.py'}:Truth", {"gt": str(folder / "gt" / "gt.txt")}))
    assert result.error is None
    for tracker in ("platform", "bytetrack"):
        scores = result.scores[tracker]
        assert scores.gt_boxes == 40  # the cars only: the tricycle is ignored, the cat is no scored class
        assert scores.reported_boxes <= 40 and scores.deta > 0.9, (tracker, scores)
    platform, bytetrack = result.scores["platform"], result.scores["bytetrack"]
    assert platform.id_switches == 0 and platform.idf1 > 0.9 and platform.hota > 0.9, platform
    # the library's defaults lose cars moving 6 px a frame (a third of their length): ids switch, the platform's don't
    assert bytetrack.id_switches > 0 and bytetrack.hota < platform.hota, bytetrack
    assert len(result.ms["detector"]) == 20 and (result.ms["platform"] > 0).all()


def test_the_set_builder_lays_out_visdrone_frames_and_rows_in_the_motchallenge_layout(tmp_path: Path) -> None:
    with script_module("build_mot_set") as build:
        visdrone = tmp_path / "VisDrone2019-MOT-val"
        (visdrone / "sequences" / "uav1").mkdir(parents=True)
        (visdrone / "annotations").mkdir()
        for frame in range(1, 6):
            cv2.imwrite(str(visdrone / "sequences" / "uav1" / f"{frame:07d}.jpg"), np.zeros((40, 60, 3), np.uint8))
        (visdrone / "annotations" / "uav1.txt").write_text("1,1,5,5,10,10,1,4,0,0\n3,1,7,5,10,10,1,4,0,2\n"
                                                           "3,2,20,20,8,8,0,0,0,0\n5,1,9,5,10,10,1,4,0,1\n")
        built = build.build_sequence(visdrone, tmp_path / "aerial-mot", "uav1", 2, 3)  # frames 2..4
        assert sorted(p.name for p in (built / "img1").iterdir()) == ["000001.jpg", "000002.jpg", "000003.jpg"]
        assert (built / "gt" / "gt.txt").read_text() == "2,1,7,5,10,10,1,4,0.25\n2,2,20,20,8,8,0,0,1\n"
        sequence = load_mot_sequence(built)
        assert (len(sequence), sequence.fps) == (3, 30.0)
        ids, boxes = sequence.scored(2)
        assert ids.tolist() == [1] and boxes.tolist() == [[7, 5, 10, 10]]
        assert sequence.ignored(2).tolist() == [[20, 20, 8, 8]]  # conf 0: VisDrone's ignored region
        assert "VisDrone2019-MOT" in (built / "source.txt").read_text()
        assert [entry[0] for entry in build.read_list()]  # the shipped list parses


def mot_set() -> Path:
    """The multi-object set; the test is skipped, saying how to build it, where it is not here."""
    how = (f"set {DATA_DIR_ENV} to the folder holding {MOT_SET}/, or build it with scripts/build_mot_set.py "
           "(docs/evaluation.md#the-multi-object-set)")
    try:
        folder = find_data_dir() / MOT_SET
    except FileNotFoundError as exc:
        wrong = f" ({exc})" if os.environ.get(DATA_DIR_ENV) else ""
        pytest.skip(f"{WANT_OF_DATA}'s multi-object part is not here{wrong}: {how}")
    if not folder.is_dir():
        pytest.skip(f"{WANT_OF_DATA}'s multi-object part is not in {folder.parent}: {how}")
    return folder


@pytest.mark.timeout(900)
def test_the_real_multi_object_set_is_scored_for_both_trackers(tmp_path: Path) -> None:
    folder = mot_set()
    sequences = find_mot_sequences([folder])
    assert mot_cli.main([str(folder), "--workers", "1", "--out", str(tmp_path)]) == 0
    summary = json.loads((tmp_path / mot_cli.RESULTS).read_text())
    assert set(summary["sequences"]) == {s.name for s in sequences}
    for tracker in ("platform", "bytetrack"):
        scores = summary["overall"]["scores"][tracker]
        assert 0 < scores["hota"] <= 1 and scores["gt_boxes"] > 0, (tracker, scores)
    ms = summary["overall"]["ms_per_frame"]
    assert ms["platform"]["mean"] < ms["detector"]["mean"]
