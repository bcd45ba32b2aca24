"""A simulated flight recorded with its video, then replayed through processors (``run:`` + ``replay:``)."""

from __future__ import annotations

import asyncio
import csv
import dataclasses
import json
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from sources.run import read_video
from sources.synthetic import SyntheticScene
from tests.core.flight_helpers import flying_core, wait_until
from tests.recording.recorder_fakes import FakeCore
from uav_tui.cli import main
from uav_tui.config import RecordingConfig, SafetyConfig, load_config
from uav_tui.core import CoreState, UavCore
from uav_tui.errors import UavError
from uav_tui.evaluation.jobs import run_jobs
from uav_tui.flight.autonomy import AutonomyGate
from uav_tui.recorded import dataset
from uav_tui.recorded.report import write_report
from uav_tui.recorded.report_replay import replay_figure
from uav_tui.recording import Recorder
from uav_tui.recording.interpolate import CONTINUOUS, DISCRETE
from uav_tui.replay.gate import autonomy_switches
from uav_tui.replay.operator import recorded_commands
from uav_tui.replay.runner import ReplayJob, recorded_processor, replay_config, replay_run
from uav_tui.tui.app import UavApp
from uav_tui.tui.screens.confirm import ConfirmScreen

BRIGHTNESS = "tests.replay.replay_processors:Brightness"
DARKNESS = "tests.replay.replay_processors:Darkness"
SLOW = "tests.replay.replay_processors:SlowBrightness"
WIDTH, HEIGHT = 160, 120


async def _fly(tmp_path: Path) -> Path:
    async with flying_core(tmp_path, processor=BRIGHTNESS, record=True, runs_dir=str(tmp_path / "runs"), save_max_hz=0,
                           source=f"synthetic:?width={WIDTH}&height={HEIGHT}&fps=30") as core:
        await core.execute("autonomy on")
        await wait_until(lambda: core.gate.executed >= 10, 15, "vectors flown under autonomy")
        await core.execute("f 2")  # the operator reverses the processor's steering
        await wait_until(lambda: core.gate.executed >= 20, 15, "reversed vectors flown under autonomy")
        await core.execute("autonomy off")
        await asyncio.sleep(1.0)
        run_dir = core.recorder.run_dir
    return run_dir


@pytest.fixture(scope="module")
def flight(tmp_path_factory) -> Path:
    """A recorded flight: takeoff, brightness-steered vectors under autonomy, reversed by F2, then autonomy off."""
    return asyncio.run(_fly(tmp_path_factory.mktemp("flight")))


def _replay(run: Path, processor: str, out: Path, speed: str = "max"):
    config = load_config(None, {"processor": processor, "runs_dir": str(out), "save_max_hz": 0})  # saves every frame
    return replay_run(ReplayJob(str(run), config, speed))


def _video_frames(path: Path) -> list[np.ndarray]:
    return list(read_video(path))


def test_the_video_has_one_frame_per_index_row_each_joining_a_frame_row(flight):
    index = pd.read_csv(flight / "video.csv", dtype={"frame_id": "Int64", "video_frame": "Int64"})
    run = dataset.load(flight)
    decoded = _video_frames(flight / "video.ts")
    encoded = index.dropna(subset=["video_frame"])
    assert run.info["video"]["codec"] in ("h264", "mjpeg") and run.info["video"]["container"] == "mpegts"
    assert len(decoded) == len(encoded) > 100
    assert encoded["video_frame"].tolist() == list(range(len(encoded)))
    assert index["t_mono_ns"].is_monotonic_increasing and index["t_mono_ns"].is_unique

    # Each processed frame's index row names it, with the capture time frames.csv has for it.
    linked = index.dropna(subset=["frame_id"]).merge(run.frames, on="frame_id", suffixes=("", "_frame"))
    assert len(linked) == index["frame_id"].notna().sum() >= 0.9 * len(encoded)
    assert (linked["t_mono_ns"] == linked["t_mono_ns_frame"]).all()
    assert (linked["seq"] == linked["seq_frame"]).all()

    # The video holds the camera image as captured: the synthetic scene, without the processor's overlay.
    scene = SyntheticScene(WIDTH, HEIGHT)
    for position in (1, len(decoded) // 2, len(decoded) - 1):
        seq = int(encoded["seq"].iloc[position])
        image = decoded[position].astype(np.float64)
        error = {n: np.sqrt(np.mean((image - scene.render(n - 1)) ** 2)) for n in range(seq - 1, seq + 2)}
        # the best match (the synthetic scene draws some neighbouring frames alike: a tie is a match)
        assert error[seq] == min(error.values()) and error[seq] < 16, f"video frame {position}: {error}"
        assert decoded[position][:16, :16].mean() < 230  # the overlay (white) was drawn after the copy


def test_a_processor_command_is_stamped_when_the_processor_took_it(flight):
    run = dataset.load(flight)
    outcome = run.events[run.events["message"] == "F2: Brightness.customize_processing(2) done"].iloc[0]
    given = run.events[run.events["message"] == "f 2"].iloc[0]
    assert outcome["command"] == "f 2" and outcome["origin"] == given["origin"] == "script"
    assert given["t_mono_ns"] < outcome["t_mono_ns"]
    # Every frame the processor started after it took F2 was reversed by it, and none before.
    frames = run.frames.dropna(subset=["gain"])
    after = frames["t_start_ns"] > outcome["t_mono_ns"]
    assert (frames.loc[after, "gain"] == -1.0).all() and (frames.loc[~after, "gain"] == 1.0).all()
    assert after.sum() >= 10 and (~after).sum() >= 10
    assert recorded_commands(flight)[0][0] == int(frames.loc[after, "t_mono_ns"].iloc[0])


def test_replay_at_max_speed_is_deterministic_and_sees_the_recorded_vehicle(flight, tmp_path):
    first = _replay(flight, BRIGHTNESS, tmp_path / "one")
    second = _replay(flight, BRIGHTNESS, tmp_path / "two")
    original, one, two = (dataset.load(path) for path in (flight, first.replay, second.replay))
    assert first.content == "video" and one.info["replay_of"]["run"] == str(flight.resolve())
    index = pd.read_csv(flight / "video.csv", dtype={"video_frame": "Int64"})
    assert len(one.frames) == len(two.frames) == index["video_frame"].notna().sum()  # every frame, in lockstep

    columns = ["t_mono_ns", "vx", "vy", "vt", "decision", "telemetry", *CONTINUOUS, *DISCRETE]
    pd.testing.assert_frame_equal(one.frames[columns].reset_index(drop=True),
                                  two.frames[columns].reset_index(drop=True))

    # The telemetry interpolated for each frame is the recorded run's.
    joined = dataset.compare(original, one)
    assert len(joined) >= 0.9 * len(one.frames)
    for name in CONTINUOUS:
        a, b = joined[f"{name}_a"].to_numpy(np.float64), joined[f"{name}_b"].to_numpy(np.float64)
        assert np.allclose(a, b, atol=1e-6, rtol=0, equal_nan=True), name
    for name in DISCRETE:
        assert joined[f"{name}_a"].equals(joined[f"{name}_b"].rename(f"{name}_a")), name

    # The same processor on the recorded video, given the operator's F2 before the frame it reached the processor
    # before in flight: reversed from the same frame on, the same vectors (up to the video's compression).
    replayed = one.events[one.events["origin"] == "replay"]
    assert replayed["message"].tolist() == ["f 2", "F2: Brightness.customize_processing(2) done"]
    assert joined["gain_a"].isin([1.0, -1.0]).all() and (joined["gain_a"] == -1.0).any()
    assert joined["gain_a"].equals(joined["gain_b"].rename("gain_a"))
    assert np.allclose(joined["vx_a"], joined["vx_b"], atol=0.05)
    assert (np.sign(joined["vx_a"]) == np.sign(joined["vx_b"]))[joined["vx_a"].abs() > 0.05].all()

    # Judged as in the flight: autonomy on exactly where it was; executed there and only there, never sent.
    executed_a = joined["decision_a"].str.startswith("executed")
    executed_b = joined["decision_b"].str.startswith("executed")
    assert executed_b.sum() >= 20
    assert (executed_a == executed_b).mean() > 0.97
    assert set(joined.loc[~executed_b, "decision_b"]) <= {"not executed: autonomy off"}

    # tmMgr.snapshot() inside the replayed processor saw the newest recorded telemetry at each capture.
    telemetry = pd.read_csv(flight / "telemetry.csv")
    times = telemetry["t_mono_ns"].to_numpy()
    newest = np.searchsorted(times, one.frames["t_mono_ns"].to_numpy(np.int64), side="right") - 1
    after = newest >= 0  # frames captured before the first telemetry saw none (t_mono_ns 0)
    frames = one.frames[after]
    assert (one.frames.loc[~after, "seen_t_mono_ns"] == 0).all() and after.mean() > 0.9
    assert (frames["seen_t_mono_ns"].to_numpy(np.int64) == times[newest[after]]).all()
    assert np.allclose(frames["seen_north_m"], telemetry["north_m"].to_numpy()[newest[after]], equal_nan=True)
    modes = telemetry["flight_mode"].fillna("").to_numpy()
    assert frames["seen_mode"].fillna("").tolist() == modes[newest[after]].tolist()


def _write_csv(path: Path, rows: list[dict[str, object]]) -> None:
    with open(path, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def test_a_command_is_due_before_the_first_frame_the_processor_started_after_it(tmp_path):
    events = [
        {"t_mono_ns": 1000, "level": "info", "kind": "command", "origin": "tui", "message": "f 2"},
        {"t_mono_ns": 1003, "level": "info", "kind": "command", "origin": "tui", "message": "F2 sent to the processor"},
        {"t_mono_ns": 1500, "level": "info", "kind": "command", "origin": "tui", "message": "arm"},
        {"t_mono_ns": 2000, "level": "error", "kind": "command", "origin": "tui", "message": "f 9: no such key"},
        {"t_mono_ns": 3000, "level": "info", "kind": "command", "origin": "web", "message": "roi 1 2 3 4"},
    ]
    _write_csv(tmp_path / "events.csv", events)
    due = [(t_ns, str(command)) for t_ns, command in recorded_commands(tmp_path)]
    assert due == [(1000, "f 2"), (3000, "roi 1 2 3 4")]  # the processor's commands, at their own time

    # Frame 2 was captured before the F2 but taken by the processor after it: the F2 reached it (live, the
    # newest frame wins, so the frame taken after a command is often older than the command).
    frames = [{"t_mono_ns": 900, "t_start_ns": 950}, {"t_mono_ns": 990, "t_start_ns": 1004},
              {"t_mono_ns": 1020, "t_start_ns": 1040}]
    _write_csv(tmp_path / "frames.csv", frames)
    assert [due for due, _ in recorded_commands(tmp_path)] == [990, 3000]  # the ROI: after the last frame

    # Recorded with the command column: the outcome rows, stamped when the processor took the command. Frame 2
    # started before it did, so the F2 is due at frame 3. A command that failed was not taken: not replayed.
    stamped = [
        {"t_mono_ns": 1000, "level": "info", "kind": "command", "origin": "tui", "message": "f 2", "command": ""},
        {"t_mono_ns": 1010, "level": "info", "kind": "command", "origin": "tui", "message": "F2 sent to the processor",
         "command": "f 2"},
        {"t_mono_ns": 1500, "level": "info", "kind": "command", "origin": "tui", "message": "arm", "command": ""},
        {"t_mono_ns": 1501, "level": "info", "kind": "command", "origin": "tui", "message": "armed", "command": "arm"},
        {"t_mono_ns": 2000, "level": "info", "kind": "command", "origin": "tui", "message": "f 3", "command": ""},
        {"t_mono_ns": 3000, "level": "error", "kind": "command", "origin": "tui", "message": "f 3: did not return",
         "command": "f 3"},
    ]
    _write_csv(tmp_path / "events.csv", stamped)
    assert [(t_ns, str(command)) for t_ns, command in recorded_commands(tmp_path)] == [(1020, "f 2")]


async def test_a_replay_reads_the_autonomy_switches_from_their_column_and_old_runs_from_the_text(tmp_path):
    core = FakeCore()
    recorder = Recorder.open(RecordingConfig(runs_dir=str(tmp_path)), {}, telemetry_expected=False)
    core.attach(recorder)
    gate = AutonomyGate(SafetyConfig(), core.telemetry, core.events)
    gate.controller = object()  # what enable() asks for; nothing is flown here
    gate.enable("tui")
    core.events.emit("info", "autonomy", "autonomy ON is what this message says; it switches nothing")
    await gate.disable("tui", hold=False)
    recorder.close()
    events_csv = recorder.run_dir / "events.csv"
    switches = autonomy_switches(events_csv)
    assert [on for _, on in switches] == [True, False]
    assert dataset.load(recorder.run_dir).events["autonomy"].dropna().tolist() == [True, False]

    # A run recorded before the column: the events' text says it.
    rows = list(csv.DictReader(events_csv.read_text().splitlines()))
    _write_csv(events_csv, [{k: v for k, v in row.items() if k != "autonomy"} for row in rows])
    assert [on for _, on in autonomy_switches(events_csv)] == [True, True, False]  # the lookalike counts there


def test_two_processors_on_the_same_flight_in_parallel_compare_frame_by_frame(flight, tmp_path):
    config = load_config(None, {"runs_dir": str(tmp_path)})
    jobs = [ReplayJob(str(flight), dataclasses.replace(config, processor=name), "max")
            for name in (BRIGHTNESS, DARKNESS)]
    bright, dark = run_jobs(replay_run, jobs, workers=2)
    joined = dataset.compare(bright.replay, dark.replay)
    assert len(joined) == bright.frames == dark.frames
    assert joined["vx_a"].notna().all() and joined["vx_b"].notna().all()
    assert np.allclose(joined["vx_a"], -joined["vx_b"])

    paths, _ = write_report(dark.replay)
    assert Path(dark.replay, "replay.png") in paths and Path(dark.replay, "replay.png").stat().st_size > 10_000


def test_a_run_recorded_before_video_replays_its_saved_frames_only(flight, tmp_path):
    old = tmp_path / "old"
    shutil.copytree(flight, old, ignore=shutil.ignore_patterns("video.*"))
    result = _replay(old, DARKNESS, tmp_path / "replays")
    with open(old / "frames.csv", newline="") as handle:
        saved = [row for row in csv.DictReader(handle) if row["image"]]
    assert result.content == "saved frames" and result.frames == len(saved) > 10


def test_the_replay_command_names_the_new_run_and_explains_bad_input(flight, tmp_path, capsys):
    runs = str(flight.parent)
    assert main(["replay", flight.name, "--runs-dir", runs, "--processor", DARKNESS, "--speed", "max",
                 "--workers", "1"]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    new_run = Path(line.rsplit("-> ", 1)[1])
    assert line.startswith(f"{flight.name}: ") and dataset.load(new_run).info["replay_of"]["name"] == flight.name
    shutil.rmtree(new_run)

    assert main(["replay", "no-such-run", "--runs-dir", runs]) == 2
    assert "neither a run folder nor a run in" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["replay", flight.name, "--runs-dir", runs, "--speed", "fast"])
    assert "--speed: speed must be a positive number or 'max'" in capsys.readouterr().err


def test_a_paced_replay_shows_recorded_frames_at_their_recorded_times(flight, tmp_path):
    result = _replay(flight, BRIGHTNESS, tmp_path, speed="8")
    index = pd.read_csv(flight / "video.csv", dtype={"video_frame": "Int64"})
    recorded = set(index.loc[index["video_frame"].notna(), "t_mono_ns"])
    frames = dataset.load(result.replay).frames
    assert len(frames) > 20 and set(frames["t_mono_ns"]) <= recorded  # a slow processor may skip some
    assert frames["t_mono_ns"].is_monotonic_increasing
    assert frames["decision"].str.startswith("executed").any()  # autonomy was on for part of the flight


def test_a_paced_replay_counts_a_frames_wait_for_the_busy_processor_as_a_live_run_does(flight, tmp_path):
    """Frames come every 17 ms at speed 2 and the processor takes 50 ms: each waits for it, as in a live run. Its
    processing starts after its capture by that wait (before: at the capture, the wait dropped) and lasts as long."""
    frames = dataset.load(_replay(flight, SLOW, tmp_path, speed="2").replay).frames
    wait_ms = (frames["t_start_ns"] - frames["t_mono_ns"]) / 1e6
    processing_ms = (frames["t_end_ns"] - frames["t_start_ns"]) / 1e6
    assert len(frames) > 20
    assert (wait_ms >= 0).all() and wait_ms.median() > 2, wait_ms.describe()
    assert processing_ms.median() >= 50, processing_ms.describe()


def test_replay_without_processor_uses_the_runs_own_and_times_are_on_the_replays_clock(flight, tmp_path, capsys):
    """``uav-tui replay RUN``: the run's processor and arguments (it used to be ``template``), said on stderr;
    latency and processing times as in the flight, not this computer's uptime minus the recorded one."""
    assert main(["replay", str(flight), "--runs-dir", str(tmp_path), "--speed", "max", "--workers", "1"]) == 0
    out, err = capsys.readouterr()
    assert f"replaying {flight.name} through {BRIGHTNESS} (its own processor)" in err.splitlines()
    assert f"frames through {BRIGHTNESS} in " in out
    replay = dataset.load(Path(out.strip().splitlines()[-1].rsplit("-> ", 1)[1]))
    assert replay.info["processor"]["spec"] == BRIGHTNESS
    frames = replay.frames
    assert (frames["t_start_ns"] == frames["t_mono_ns"]).all()  # taken when shown, at its capture time
    processing_s = (frames["t_end_ns"] - frames["t_start_ns"]) / 1e9
    latency_s = (frames["t_vector_ns"] - frames["t_mono_ns"]) / 1e9
    assert processing_s.between(0, 5).all() and latency_s.between(0, 5).all()
    text = write_report(replay.path)[1]
    p50 = float(text.split("latency capture->result: p50 ")[1].split(" ms")[0])
    assert 0 <= p50 < 5000  # before: the hours between the flight and the replay


def test_replay_png_labels_flight_and_replay_apart_and_keeps_its_title_inside(flight, tmp_path):
    result = _replay(flight, DARKNESS, tmp_path)
    figure = replay_figure(dataset.load(result.replay))
    assert figure is not None
    FigureCanvasAgg(figure).draw()
    title = figure._suptitle.get_window_extent()
    assert title.x0 >= 0 and title.x1 <= figure.bbox.width  # not clipped
    labels = [text.get_text() for text in figure.axes[0].get_legend().get_texts()]
    assert labels[0] == f"flight ({BRIGHTNESS})" and f"replay ({DARKNESS})" in labels
    box = figure.axes[2]  # both processors report a box: its centre is drawn, not an empty panel
    assert box.get_ylabel() == "box centre, px" and all(np.isfinite(line.get_ydata()).any() for line in box.lines)


async def test_quitting_a_replay_in_the_dashboard_asks_nothing_about_the_recorded_vehicle(flight, tmp_path):
    config = replay_config(ReplayJob(str(flight), load_config(None, {"processor": BRIGHTNESS,
                                                                     "runs_dir": str(tmp_path)}), "1"))
    app = UavApp(UavCore(config))
    async with app.run_test(size=(80, 24)) as pilot:
        deadline = asyncio.get_running_loop().time() + 30
        while not (app.core.state is CoreState.RUNNING and app.core.telemetry.snapshot().armed):
            assert asyncio.get_running_loop().time() < deadline, "the recorded vehicle never armed"
            await pilot.pause(0.05)
        await pilot.press("q")
        await pilot.pause(0.3)
        assert not isinstance(app.screen, ConfirmScreen)  # before: "The vehicle is ARMED. Quit? ..."
        while app.core.state is not CoreState.STOPPED:
            assert asyncio.get_running_loop().time() < deadline + 15, "the replay did not stop"
            await pilot.pause(0.05)


def test_the_runs_own_processor_is_found_by_its_full_path_and_its_absence_is_said(tmp_path):
    mine = tmp_path / "algos" / "mine.py"
    mine.parent.mkdir()
    mine.write_text("")
    run = tmp_path / "run"
    run.mkdir()
    (run / "run.json").write_text(json.dumps({"processor": {"spec": "algos/mine.py:Mine", "path": str(mine),
                                                            "name": "uav_tui_user_mine:Mine", "kwargs": {"gain": 2}}}))
    assert recorded_processor(run) == (f"{mine}:Mine", {"gain": 2})  # the flight started in another folder
    (run / "run.json").write_text("{}")
    with pytest.raises(UavError, match="does not say which processor the run had: give --processor"):
        recorded_processor(run)


def test_a_lock_command_is_due_at_the_frame_the_lock_first_acted_on(tmp_path):
    given = [("lock 3", 1000), ("arm", 2500), ("hold", 3500), ("lock 9", 3600)]  # as each came (no command column)
    _write_csv(tmp_path / "events.csv", [{"t_mono_ns": t, "level": "info", "kind": "command", "origin": "tui",
                                          "message": text, "command": ""} for text, t in given])
    # Frame 1 ended before the lock (990 ns) but was handled after it (its result on its way to the loop); the hold
    # released the lock at frame 4; the arm was given while nothing was locked, and track 9 was on no frame.
    locks = ["", 3, 3, 3, "", "", ""]
    _write_csv(tmp_path / "frames.csv", [{"t_mono_ns": 100 + 1000 * i, "t_start_ns": 150 + 1000 * i - 500,
                                          "t_end_ns": 990 + 1000 * (i - 1), "lock_track": lock}
                                         for i, lock in enumerate(locks)])
    due = [(t_ns, str(command)) for t_ns, command in recorded_commands(tmp_path)]
    assert due == [(1100, "lock 3"), (4100, "unlock"), (5100, "lock 9")]
    # Recorded before the lock column: at the first frame that ended after it; a vehicle command never.
    _write_csv(tmp_path / "frames.csv", [{"t_mono_ns": 100 + 1000 * i, "t_start_ns": 150 + 1000 * i - 500,
                                          "t_end_ns": 990 + 1000 * (i - 1)} for i in range(len(locks))])
    assert [(t_ns, str(command)) for t_ns, command in recorded_commands(tmp_path)] == [(2100, "lock 3"),
                                                                                        (4100, "lock 9")]
