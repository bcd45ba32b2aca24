"""``uav-tui bench``: the table of each processor's FPS and CPU on this computer (its form, not its figures)."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from uav_tui.cli import main


def test_the_table_and_its_json_have_a_row_per_processor_and_resolution(tmp_path: Path,
                                                                         capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "bench.json"
    code = main(["bench", "--processors", "template,nope", "--resolutions", "160x120,320x240", "--seconds", "0.5",
                 "--warm-up", "0.3", "--out", str(out)])
    assert code == 1  # a row that could not be measured
    rows = json.loads(out.read_text())["rows"]
    assert [(r["processor"], r["resolution"]) for r in rows] == [
        ("template", "160x120"), ("nope", "160x120"), ("template", "320x240"), ("nope", "320x240")]
    measured = [r for r in rows if r["processor"] == "template"]
    assert all(r["fps"] > 0 and r["cpu_ms_per_frame"] > 0 and r["frames"] >= 2 for r in measured)
    assert all("not a known name" in r["error"] for r in rows if r["processor"] == "nope")
    printed = capsys.readouterr().out
    header, template, nope = printed.split("\n\n")[-1].splitlines()[:3]
    assert header.split() == ["processor", "160x120", "FPS", "160x120", "CPU", "ms", "320x240", "FPS", "320x240",
                              "CPU", "ms"]
    assert template.split() == ["template", *(str(v) for r in measured for v in (f"{r['fps']:g}",
                                                                                   f"{r['cpu_ms_per_frame']:g}"))]
    assert nope.split() == ["nope", "-", "-", "-", "-"]
    assert f"saved {out}" in printed


def test_a_users_clip_is_resized_and_measured(tmp_path: Path) -> None:
    clip = tmp_path / "mine.mp4"
    writer = cv2.VideoWriter(str(clip), cv2.VideoWriter.fourcc(*"mp4v"), 30, (64, 48))
    for i in range(20):
        writer.write(np.full((48, 64, 3), i * 10, np.uint8))
    writer.release()
    out = tmp_path / "bench.json"
    assert main(["bench", "--processors", "template", "--resolutions", "96x72", "--video", str(clip),
                 "--seconds", "0.3", "--warm-up", "0.2", "--out", str(out)]) == 0
    document = json.loads(out.read_text())
    assert document["video"] == str(clip) and document["rows"][0]["fps"] > 0


@pytest.mark.parametrize("argv", [["--resolutions", "640"], ["--seconds", "0"], ["--video", "/nonexistent.mp4"]],
                         ids=["resolution", "seconds", "video"])
def test_bad_arguments_say_so_before_anything_runs(argv: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exited:
        main(["bench", *argv])
    assert exited.value.code == 2 and "uav-tui bench: error:" in capsys.readouterr().err
