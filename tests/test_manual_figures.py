"""The figures in docs/benchmarks.md are what ``scripts/manual_figures.py`` writes from the committed benchmark JSON."""

from __future__ import annotations

import json
from pathlib import Path

from tests.scripts import script_module

ROOT = Path(__file__).resolve().parents[1]


def test_the_manual_figures_are_the_ones_the_committed_json_gives() -> None:
    text = (ROOT / "docs" / "benchmarks.md").read_text()
    assert all(f"<!-- bench:{name} -->" in text for name in ("tracking", "precland", "geolocation"))
    stale = "docs/benchmarks.md is stale: run .venv/bin/python scripts/manual_figures.py"
    with script_module("manual_figures") as figures:
        assert figures.render(text) == text, stale


def test_a_block_is_rewritten_from_its_json_and_nothing_else_moves(tmp_path: Path) -> None:
    result = {"data": "/x/aerial-tracking", "sequences": 19, "workers": 1, "threads": 1, "missing": {},
              "trackers": {"csrt mode=fast": {"success_auc": 0.50612, "precision_20": 0.7, "ms_mean": 6.31,
                                              "lost_while_visible": 4, "lost_while_visible_share": 0.0013}},
              "goals": {"csrt mode=fast": {"ms/frame over cv:csrt's": {"goal": "<= 0.5", "value": 0.41,
                                                                      "pass": True}}}}
    (tmp_path / "tracking.json").write_text(json.dumps(result))
    text = "before\n<!-- bench:tracking -->\nfast csrt 0.528, 1 frame lost\n<!-- /bench:tracking -->\nafter\n"
    with script_module("manual_figures") as figures:
        written = figures.render(text, tmp_path)
    assert written.startswith("before\n<!-- bench:tracking -->\n| tracker |")
    assert written.endswith("<!-- /bench:tracking -->\nafter\n") and "0.528" not in written
    assert "| `csrt mode=fast` | 0.506 | 0.700 | 4 (0.1%) | 6.3 |" in written
    assert "- csrt mode=fast: ms/frame over cv:csrt's 0.41 (<= 0.5: met)" in written
    assert "19 sequences of `aerial-tracking`, 1 job(s) at a time" in written


def test_the_geolocation_block_has_a_row_per_height_and_case_and_the_flights_when_flown(tmp_path: Path) -> None:
    result = json.loads((ROOT / "scripts" / "results" / "geolocation.json").read_text())
    flown = result["flight_recorded"]["50m"]["flying_2ms"]
    flown["error"]["p95_m"] = 1.234
    (tmp_path / "geolocation.json").write_text(json.dumps(result))
    text = "<!-- bench:geolocation -->\n<!-- /bench:geolocation -->\n"
    with script_module("manual_figures") as figures:
        written = figures.render(text, tmp_path)
        assert f"| 50 m | flight, at 2 m/s | {flown['frames']} | {flown['error']['p50_m']} m | 1.234 m |" in written
        assert written.count("| 20 m | views, ") == written.count("| 50 m | views, ") == 3
        assert "50 m: terrain" in written and "(<= 2.0: met)" in written
        del result["flight_recorded"]  # --no-flight
        (tmp_path / "geolocation.json").write_text(json.dumps(result))
        without = figures.render(text, tmp_path)
    assert "flight," not in without and "came from" not in without and "| 50 m | views, camera down, level |" in without
