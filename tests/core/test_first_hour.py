"""What a new user meets first: ``--help``, error lines, the headless status line, the end of a run, ``runs``."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from controllers.base import Telemetry
from sources.buffer import Frame
from uav_tui.cli import build_parser
from uav_tui.config import RecordingConfig, SafetyConfig
from uav_tui.errors import CommandError
from uav_tui.events import EventLog
from uav_tui.flight.autonomy import AutonomyGate
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.headless import format_status, load_script
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.wire import FrameOutcome
from uav_tui.recorded.runs_cli import main as tools_main
from uav_tui.recording import Recorder
from uav_tui.stats import PipelineStats
from uav_tui.status import CoreStatus

ROOT = Path(__file__).resolve().parents[2]


def uav(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "uav_tui", *args], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=60)


def test_help_names_only_what_exists_with_clean_group_titles() -> None:
    text = build_parser().format_help()
    assert "ARCHITECTURE" not in text
    assert "report [RUN]" in text
    titles = [line for line in text.splitlines() if line and not line[0].isspace() and line.endswith(":")]
    assert "safety ([safety]):" in titles and "recording ([recording]):" in titles
    assert not [title for title in titles if title[-2] in ".`"], titles


def _status(**changes: object) -> CoreStatus:
    values = dict(
        telemetry=Telemetry(rel_alt_m=10.0, north_m=2.04, east_m=-0.5, flight_mode="OFFBOARD", armed=True,
                            in_air=True),
        pipeline=PipelineStats(30, 30, 1, 2, 1, 2, 100, 0, 0, 0),
        source_uri="sim:", source={}, processor="p", capabilities=frozenset(), processor_error=None, fc="sim",
        fc_description="sim", heartbeat_age_s=0.2, autonomy=True, autonomy_stop_reason="",
        last_vector=(-0.71, 0.05, 1.0), last_decision="executed", vectors_executed=3, vectors_rejected=0)
    return CoreStatus(**{**values, **changes})


def test_status_line_shows_position_and_the_vector_with_its_decision() -> None:
    line = format_status(_status(), 12.0)
    assert "alt 10.0m N 2.0 E -0.5m" in line
    assert line.endswith("auto ON vec -0.71,+0.05m/s 1.0s (executed)")
    line = format_status(_status(autonomy=False, last_decision="not executed: autonomy off"), 12.0)
    assert line.endswith("auto OFF vec -0.71,+0.05m/s 1.0s (not executed: autonomy off)")


def test_status_line_without_position_or_vector() -> None:
    line = format_status(_status(telemetry=Telemetry(), last_vector=None, last_decision=""), 1.0)
    assert " N " not in line and "vec" not in line and line.endswith("auto ON")


def test_script_typo_suggests_the_command(tmp_path: Path) -> None:
    script = tmp_path / "flight.txt"
    script.write_text("arm\ntakeof 5\n")
    with pytest.raises(CommandError, match=r"flight.txt:2: unknown command 'takeof'; did you mean 'takeoff'\?"):
        load_script(script)


def test_every_command_line_error_has_the_same_prefix(tmp_path: Path) -> None:
    (tmp_path / "bright.py").write_text("class BrightForward:\n    def photo_processing(self, frame):\n        pass\n")
    (tmp_path / "flight.txt").write_text("takeof\n")
    cases = {
        ("--bogus",): "uav-tui: error: unrecognized arguments: --bogus",
        ("--max-speed", "50"): "uav-tui: error: command line: --max-speed = 50.0 is out of range",
        ("--script", "flight.txt"): "uav-tui: error: flight.txt:1: unknown command 'takeof'",
        ("--processor", "bright.py"): "uav-tui: error: processor 'bright.py' names a file but no class: use "
                                      "bright.py:BrightForward",
        ("report", "nothing-here"): "uav-tui report: error: nothing-here is neither a run folder",
    }
    for args, expected in cases.items():
        flags = () if args[0] in ("runs", "report") else ("--no-ui", "--no-record", "--duration", "5")
        result = uav(*args, *flags, cwd=tmp_path)
        assert result.returncode == 2, (args, result.stdout)
        assert result.stderr.splitlines()[-1].startswith(expected), (args, result.stderr)


def test_a_headless_run_ends_by_saying_where_it_was_saved_and_how_fast_it_started(tmp_path: Path) -> None:
    result = uav("--no-ui", "--duration", "2", "--runs-dir", str(tmp_path / "runs"), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    run_dir = next((tmp_path / "runs").iterdir())
    assert result.stdout.splitlines()[-1] == (f"run saved in {run_dir}; plots and summary: uav-tui report {run_dir} "
                                              "(all runs: uav-tui runs)")
    assert "first frame processed" in result.stdout
    result = uav("--no-ui", "--json", "--duration", "2", "--runs-dir", str(tmp_path / "runs"), cwd=tmp_path)
    records = [json.loads(line) for line in result.stdout.splitlines()]
    assert 0 < [r for r in records if "pipeline" in r][-1]["startup_s"] < 60
    assert Path(records[-1]["run_dir"]).parent == tmp_path / "runs"


def test_runs_lists_processor_and_source_without_passwords(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for spec, uri in (("mine.py:Mine", "rtsp://pilot:secret@192.0.2.1/cam"), ("csrt", "usb:0\x1b[31m")):
        Recorder.open(RecordingConfig(runs_dir=str(tmp_path)), {"processor": {"spec": spec, "name": "x:Y"},
                      "source": {"uri": uri}}, telemetry_expected=False,
                      started_wall_ns=1_790_000_000_000_000_000 + len(spec) * 10**9).close()
    assert tools_main("runs", ["--runs-dir", str(tmp_path)]) == 0
    header, first, second = capsys.readouterr().out.splitlines()
    assert header.split()[-2:] == ["processor", "source"]
    assert first.split()[-2:] == ["csrt", "usb:0\\x1b[31m"]  # the one escaping function, text.safe
    assert second.split()[-2:] == ["mine.py:Mine", "rtsp://pilot:***@192.0.2.1/cam"]


def test_a_rejected_vector_leaves_no_stale_vector_beside_its_decision() -> None:
    gate = AutonomyGate(SafetyConfig(), TelemetryManager(None), EventLog())
    for vector in ((0.5, 0.0, 1.0), (math.nan, 0.0, 1.0)):
        result = ProcessedFrame(Frame(np.zeros((4, 4, 3), np.uint8), 1, time.monotonic_ns(), time.time_ns()),
                                FrameOutcome(0, 0, vector=vector))
        gate.consider(result)
        line = format_status(_status(last_vector=gate.last_vector, last_decision=gate.last_decision), 1.0)
    assert gate.last_vector is None and " vec " not in line and line.endswith(f"auto ON ({gate.last_decision})")


def test_a_headless_run_without_vehicle_or_web_page_imports_nothing_heavy(tmp_path: Path) -> None:
    """Start-up time (``scripts/bench_startup.py``): these load only when a plot, the dashboard, the web page
    or a vehicle asks for them."""
    heavy = ("matplotlib", "pandas", "textual", "aiortc", "aiohttp", "mavsdk", "skimage", "scipy")
    code = ("import sys; from uav_tui.cli import main; code = main(['--no-ui', '--duration', '1', '--no-record']); "
            f"print(sorted(name for name in {heavy!r} if name in sys.modules)); sys.exit(code)")
    result = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)},
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[-1] == "[]"


def test_error_lines_point_at_the_fix(tmp_path: Path) -> None:
    (tmp_path / "top.toml").write_text("max_speed = 2\n")
    (tmp_path / "typo.toml").write_text("[safety]\nmax_sped = 2\n")
    (tmp_path / "gain.py").write_text("class Gain:\n    def __init__(self, gain, offset=0):\n        pass\n\n"
                                      "    def photo_processing(self, frame):\n        pass\n")
    fc_hint = ("is not a name uav-tui knows: use 'sim' for the built-in simulated vehicle, 'none' for no vehicle, "
               "or a MAVLink connection string (a PX4 SITL: udpin://0.0.0.0:14540")
    cases = {
        ("--config", "top.toml"): "uav-tui: error: top.toml: 'max_speed' belongs under [safety]",
        ("--config", "typo.toml"): "uav-tui: error: typo.toml: unknown key 'safety.max_sped'; did you mean "
                                   "'max_speed'?",
        ("--fc", "simulator"): f"uav-tui: error: flight controller 'simulator' {fc_hint}",
        ("--fc", "px4"): f"uav-tui: error: flight controller 'px4' {fc_hint}",
        ("--max-sped", "2"): "uav-tui: error: unrecognized arguments: --max-sped 2; did you mean --max-speed?",
        ("--processor", "gain.py:Gain"): "uav-tui: error: Gain (" + str(tmp_path / "gain.py") + ") needs the "
                                         "constructor argument gain: give --processor-arg gain=... (or "
                                         "[processor_args] in uav.toml)",
        ("replay", "run", "--procesor"): "uav-tui replay: error: unrecognized arguments: --procesor; did you mean "
                                         "--processor?",
        ("sim", "--mavlink-prt", "1"): "uav-tui sim: error: unrecognized arguments: --mavlink-prt 1; did you mean "
                                       "--mavlink-port?",
        ("repaly",): "uav-tui: error: unrecognized arguments: repaly; did you mean uav-tui replay?",
    }
    for args, expected in cases.items():
        flags = ("--no-ui", "--no-record", "--duration", "5") if args[:1] not in (("replay",), ("sim",)) else ()
        result = uav(*args, *flags, cwd=tmp_path)
        assert result.returncode == 2, (args, result.stdout)
        lines = result.stderr.splitlines()
        assert len(lines) == 1, (args, result.stderr)  # one line, no usage
        assert lines[0].startswith(expected), (args, lines[0])


def test_the_demo_counts_its_start_up_from_uav_tuis_start_not_from_its_setup(tmp_path: Path) -> None:
    """scripts/demo.sh sets up first (a minute on a fresh clone); the time to the first frame is uav-tui's own."""
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "demo.sh").write_bytes((ROOT / "scripts" / "demo.sh").read_bytes())
    (tmp_path / "scripts" / "setup.sh").write_text("sleep 10\ndate +%s.%N > setup-done\n")  # a slow setup
    (tmp_path / ".venv" / "bin").mkdir(parents=True)
    (tmp_path / ".venv" / "bin" / "uav-tui").write_text(f"#!/bin/sh\nexec {sys.executable} -m uav_tui \"$@\"\n")
    (tmp_path / ".venv" / "bin" / "uav-tui").chmod(0o755)
    (tmp_path / "empty.txt").write_text("")
    result = subprocess.run(["bash", str(tmp_path / "scripts" / "demo.sh"), "--no-ui", "--json", "--duration", "2",
                             "--no-record", "--fc", "none", "--source", "synthetic:", "--processor", "template",
                             "--script", str(tmp_path / "empty.txt")],
                            env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True, timeout=90)
    since_setup_s = time.time() - float((tmp_path / "setup-done").read_text())
    assert result.returncode == 0, result.stderr
    startup = [json.loads(line)["startup_s"] for line in result.stdout.splitlines() if '"startup_s"' in line]
    # The first frame came after the setup, so uav-tui's start-up fits in the time since (before: 10 s more).
    assert 0 < [s for s in startup if s is not None][-1] < since_setup_s


def test_more_error_lines_point_at_the_fix(tmp_path: Path) -> None:
    """#46: a misspelt section, a duration that leaves an empty run, a text for a number, a failed import."""
    (tmp_path / "safty.toml").write_text("[safty]\nmax_speed = 2\n")
    (tmp_path / "nothing.toml").write_text("[zzz]\na = 1\n")
    (tmp_path / "gain.py").write_text("class Gain:\n    def __init__(self, gain: float = 1.0):\n        pass\n\n"
                                      "    def photo_processing(self, frame):\n        pass\n")
    (tmp_path / "typo.py").write_text("import scipyy\n\n\nclass A:\n    def photo_processing(self, frame):\n"
                                      "        pass\n")
    (tmp_path / "absent.py").write_text("import notamodule_xyz\n\n\nclass A:\n    def photo_processing(self, frame):\n"
                                        "        pass\n")
    cases = {
        ("--config", "safty.toml"): "safty.toml: unknown table [safty]; did you mean [safety]?",
        ("--config", "nothing.toml"): "nothing.toml: unknown table [zzz]; the sections are [safety], [envelope], "
                                      "[recording], [web], [sim], [camera]",
        ("--duration", "-5"): "argument --duration: -5 must be a positive number of seconds",
        ("--duration", "nan"): "argument --duration: nan must be a positive number of seconds",
        ("--processor", "gain.py:Gain", "--processor-arg", "gain=abc"): "constructor argument gain must be a number "
                                                                        "(float), got str 'abc'",
        ("--processor", "typo.py:A"): "No module named 'scipyy'; no module 'scipyy' is installed, but 'scipy' is: "
                                      "is the import misspelt?",
        ("--processor", "absent.py:A"): f"install it into uav-tui's Python: {sys.executable} -m pip install "
                                        "notamodule_xyz",
    }
    for args, expected in cases.items():
        flags = ("--no-ui", "--no-record") + (() if "--duration" in args else ("--duration", "5"))
        result = uav(*args, *flags, cwd=tmp_path)
        assert result.returncode == 2, (args, result.stdout)
        (line,) = result.stderr.splitlines()  # one line, no usage, before anything started
        assert line.startswith("uav-tui: error: ") and expected in line, (args, line)
