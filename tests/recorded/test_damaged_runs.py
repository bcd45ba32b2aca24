"""``report`` and ``dataset.load`` read every run the platform writes (NaN, inf, -1e308, constant fields), and a
damaged run gives one line naming the file, the line and what is wrong, and still draws what can be drawn."""

from __future__ import annotations

import csv
import io
import json
import math
import shutil
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from tests.recording.recorder_fakes import FakeCore
from uav_tui.config import RecordingConfig
from uav_tui.recorded import dataset
from uav_tui.recorded.report import PLOTS
from uav_tui.recorded.runs_cli import main as tools_main
from uav_tui.recording import Recorder

VECTORS = [(0.5, 0.0, 1.0), (math.nan, 0.0, 1.0), (math.inf, 0.2, 1.0), None]


@pytest.fixture(scope="module")
def odd_run(tmp_path_factory) -> Path:
    """A run whose processor returned NaN and inf vectors and saved a constant -1e308, inf and NaN fields."""
    core = FakeCore()
    recorder = Recorder.open(RecordingConfig(runs_dir=str(tmp_path_factory.mktemp("runs"))),
                             {"processor": {"name": "odd"}}, telemetry_expected=True)
    core.attach(recorder)
    image = np.zeros((48, 64, 3), np.uint8)
    for i in range(40):
        core.telemetry.apply({"north_m": 0.1 * i, "east_m": 0.0, "rel_alt_m": 5.0, "yaw_deg": 0.0, "vn_ms": 0.5,
                              "ve_ms": 0.0, "armed": True, "in_air": True, "satellites": 12})
        time.sleep(0.004)

        def frame(result, i=i):
            core.telemetry.save(image, floor=-1e308, score=[math.inf, math.nan, 1e300, 0.5][i % 4], constant=7)
            result.vector = VECTORS[i % 4]
            result.decision = "executed" if i % 4 == 0 else "rejected: not finite" if i % 4 in (1, 2) else "no vector"
        core.process(image, i + 1, frame)
    core.events.emit("info", "autonomy", "autonomy ON", "tui")
    recorder.close()
    return recorder.run_dir


def _report(run_dir: Path, capsys: pytest.CaptureFixture[str]) -> list[str]:
    """``uav-tui report RUN``: the lines that say the run is damaged, after checking every plot was written."""
    for name in PLOTS:
        (run_dir / name).unlink(missing_ok=True)
    assert tools_main("report", [str(run_dir)]) == 0
    captured = capsys.readouterr()
    for name in PLOTS:
        assert (run_dir / name).read_bytes().startswith(b"\x89PNG"), name
    assert captured.err == ""
    return [line for line in captured.out.splitlines() if line.startswith("damaged run:")]


def test_nan_and_inf_vectors_and_huge_constant_fields_load_and_report(odd_run, capsys):
    run = dataset.load(odd_run)
    assert run.problems == ()
    vx = run.frames["vx"].to_numpy()
    assert vx[0] == 0.5 and math.isnan(vx[1]) and vx[2] == math.inf and math.isnan(vx[3])
    assert str(run.frames["vx"].dtype) == "float64" and (run.frames["floor"] == -1e308).all()
    assert _report(odd_run, capsys) == []


def _edit(name: str, change: Callable[[str], str]) -> Callable[[Path], None]:
    def apply(run_dir: Path) -> None:
        path = run_dir / name
        path.write_text(change(path.read_text()))
    return apply


def _edit_bytes(name: str, change: Callable[[bytes], bytes]) -> Callable[[Path], None]:
    def apply(run_dir: Path) -> None:
        path = run_dir / name
        path.write_bytes(change(path.read_bytes()))
    return apply


def _line(text: str, number: int, change: Callable[[str], str]) -> str:
    lines = text.split("\n")
    lines[number - 1] = change(lines[number - 1])
    return "\n".join(lines)


def _set_field(text: str, number: int, column: str, value: str) -> str:
    rows = list(csv.reader(text.splitlines()))
    rows[number - 1][rows[0].index(column)] = value
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerows(rows)
    return out.getvalue()


CORRUPTIONS = {
    "run.json cut short": (_edit("run.json", lambda text: text[: len(text) // 2]), "run.json line ", "not valid JSON"),
    "run.json not an object": (_edit("run.json", lambda text: "[1, 2]\n"), "run.json line 1", "not an object"),
    "run.json wrong types": (_edit("run.json", lambda text: json.dumps({**json.loads(text), "processor": "csrt"})),
                             "run.json", "processor is not what uav-tui writes"),
    "binary bytes": (_edit_bytes("frames.csv", lambda data: data.replace(b"no vector", b"no \xff\xfe\x80", 1)),
                     "frames.csv line 5", "not UTF-8"),
    "empty file": (_edit("frames.csv", lambda text: ""), "frames.csv", "empty"),
    "ragged row": (_edit("frames.csv", lambda text: _line(text, 7, lambda line: line + ",1,2")), "frames.csv line 7",
                   "fields where the header has"),
    "row cut short": (_edit("telemetry.csv", lambda text: text[: text.rindex(",", 0, len(text) - 40)]),
                      "telemetry.csv line 41", "fields where the header has"),
    "NUL bytes": (_edit_bytes("telemetry.csv", lambda data: data + b"\0" * 4096), "telemetry.csv line 42",
                  "NUL bytes"),  # power lost after the file grew, before its data was written
    "text in a number column": (_edit("frames.csv", lambda text: _set_field(text, 9, "vy", "fast")),
                                "frames.csv line 9", "column vy: 'fast' is not a number"),
    "text in a whole-number column": (_edit("telemetry.csv", lambda text: _set_field(text, 3, "satellites", "12.5")),
                                      "telemetry.csv line 3", "column satellites: '12.5' is not a whole number"),
    "missing header": (_edit("frames.csv", lambda text: text.split("\n", 1)[1]), "frames.csv line 1",
                       "no header line"),
    "bad extra JSON": (_edit("frames.csv", lambda text: text.replace('"{""floor""', '"{floor', 1)), "frames.csv",
                       "the extra of frame_id 1 is not a JSON object"),
}


@pytest.mark.parametrize("case", list(CORRUPTIONS))
def test_a_damaged_run_gives_one_line_naming_file_and_line_and_draws_the_rest(case, odd_run, tmp_path, capsys):
    damage, where, what = CORRUPTIONS[case]
    run_dir = tmp_path / odd_run.name
    shutil.copytree(odd_run, run_dir)
    damage(run_dir)
    run = dataset.load(run_dir)
    assert len(run.problems) == 1, run.problems
    assert f"{run_dir}/{where}" in run.problems[0] and what in run.problems[0], run.problems
    assert len(run.telemetry) >= 30 or "telemetry" in where  # the undamaged tables are all there
    assert len(run.frames) >= 30 or "frames" in where
    lines = _report(run_dir, capsys)
    assert lines == [f"damaged run: {run.problems[0]}"]


def _locate(text: str, *lines: int) -> str:
    """frames.csv with the rows on ``lines`` geo-located (as a frame with a box, a camera and GPS is)."""
    for number in lines:
        for column, value in (("target_lat_deg", "47.3977"), ("target_lon_deg", "8.5456"), ("target_alt_m", "488.0"),
                              ("target_uncertainty_m", "0.5"), ("target_status", "ok")):
            text = _set_field(text, number, column, value)
    return text


def test_export_leaves_out_a_located_row_without_frame_id_and_says_which(odd_run, tmp_path, capsys):
    run_dir = tmp_path / odd_run.name
    shutil.copytree(odd_run, run_dir)
    _edit("frames.csv", lambda text: _set_field(_locate(text, 3, 4), 4, "frame_id", "nan"))(run_dir)
    assert tools_main("export", [str(run_dir), "--geojson"]) == 0  # before: a traceback (int() of NA)
    out = capsys.readouterr().out
    assert f"damaged run: {run_dir}/frames.csv line 4: column frame_id: 'nan' is not a whole number" in out
    assert "1 geo-located rows without a frame_id were left out" in out
    points = json.loads((run_dir / "track.geojson").read_text())["features"]
    assert [p["properties"]["frame_id"] for p in points if p["properties"]["kind"] == "target"] == [2]


def test_replay_names_frames_csv_for_a_frame_time_that_is_not_a_number(odd_run, tmp_path, capsys):
    from uav_tui.cli import main

    run_dir = tmp_path / odd_run.name
    shutil.copytree(odd_run, run_dir)
    _edit("frames.csv", lambda text: _set_field(text, 2, "t_mono_ns", "nan"))(run_dir)
    assert main(["replay", str(run_dir), "--processor", "template", "--runs-dir", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert f"{run_dir}/frames.csv line 2: t_mono_ns 'nan' is not a whole number" in error  # before: telemetry.csv
    assert "telemetry.csv" not in error
