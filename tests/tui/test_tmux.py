"""End to end, as an operator over SSH: ``python -m uav_tui`` in a real terminal (tmux), keys, screen, hang-up.

Flying tests run the simulator on its own, so that its ground truth outlives uav-tui."""

from __future__ import annotations

import csv
import itertools
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import psutil
import pytest

from controllers.sim.launcher import SimVehicle
from controllers.sim.truth import TruthClient
from tests.core.flight_helpers import NO_FAILSAFE, STEERING_PROCESSOR, speed
from tests.videos import damaged_aerial_video

ROOT = Path(__file__).parents[2]

LOG_COLUMN = 40
"""Where the event log starts on an 80-column screen (the left column of panels is 40 wide)."""

pytestmark = pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")


class Tmux:
    """One private tmux server (its own socket in the test's tmp_path) running one 80x24 session."""

    def __init__(self, tmp_path: Path) -> None:
        self.socket = str(tmp_path / "tmux.sock")  # its own server, its socket removed with tmp_path
        self.status = tmp_path / "status"

    def tmux(self, *args: str) -> str:
        return subprocess.run(["tmux", "-S", self.socket, *args], check=True, capture_output=True, text=True,
                              timeout=10).stdout

    def start(self, *flags: str, tmp_path: Path, colorterm: str = "") -> None:
        command = [sys.executable, "-m", "uav_tui", "--source", "synthetic:?fps=30", "--processor",
                   f"{ROOT / 'tests/tui/procs.py'}:RecordingProcessor", "--no-record", "--runs-dir",
                   str(tmp_path / "runs"), *flags]
        # The shell survives a hang-up (it traps SIGHUP, doing nothing) so that it can write the exit status;
        # it writes it whole or not at all (renamed into place), so a test never reads it half-written. A trap
        # (not ignoring it) leaves SIGHUP's default to the programs it starts: a hang-up reaches every process
        # of the job, as over SSH.
        script = (f"trap : HUP; cd {shlex.quote(str(tmp_path))}; {shlex.join(command)}; "
                  f"echo $? > {self.status}.part; mv {self.status}.part {self.status}")
        env = f"env -u COLORTERM PYTHONPATH={shlex.quote(str(ROOT))} TERM=xterm-256color"
        if colorterm:
            env += f" COLORTERM={colorterm}"
        self.tmux("new-session", "-d", "-x", "80", "-y", "24", f"{env} sh -c {shlex.quote(script)}")

    def screen(self, escapes: bool = False) -> str:
        return self.tmux("capture-pane", "-p", *(["-e"] if escapes else []))

    def log_shows(self, text: str) -> bool:
        """Whether the event log (the right half of the 80-column screen) shows ``text``; it wraps lines."""
        try:
            screen = self.screen()
        except subprocess.CalledProcessError:  # the session ended with the program
            return False
        log = "".join(line[LOG_COLUMN:] for line in screen.splitlines())
        log = re.sub("[\u2580-\u259f]", "", log)  # the scrollbar's blocks, once the log outgrows its panel
        return "".join(text.split()) in "".join(log.split())

    def keys(self, *keys: str) -> None:
        self.tmux("send-keys", *keys)

    def app_pid(self) -> int:
        shell = psutil.Process(int(self.tmux("display-message", "-p", "#{pane_pid}").strip()))
        return next(child.pid for child in shell.children() if "python" in child.name().lower())

    def kill(self) -> None:
        subprocess.run(["tmux", "-S", self.socket, "kill-server"], capture_output=True, timeout=10)


@pytest.fixture
def tmux(tmp_path: Path):
    session = Tmux(tmp_path)
    yield session
    session.kill()


def wait(condition: Callable[[], object], timeout: float, what: str) -> object:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        result = condition()
        if result:
            return result
        time.sleep(0.1)
    pytest.fail(f"timed out waiting for {what}")


def test_dashboard_in_a_real_terminal_takes_keys_and_quits(tmux, tmp_path):
    tmux.start("--fc", "none", tmp_path=tmp_path)
    wait(lambda: re.search(r"proc +[1-9]", tmux.screen()), 30, "the dashboard with frames flowing")
    screen = tmux.screen()
    for text in ("Telemetry", "Pipeline", "Algorithm", "Preview", "Events", "AUTONOMY", "Quit", "Hold"):
        assert text in screen, text
    assert len(screen.splitlines()) <= 24 and all(len(line) <= 80 for line in screen.splitlines())
    # The processor's own process, whole on 80 columns: the name gives way to its state, pid and memory.
    child = processor_process(psutil.Process(tmux.app_pid()))
    assert re.search(rf"^ proc +Rec\S*… running, pid {child.pid}, \d+ MB ", screen, re.MULTILINE), screen
    tmux.keys("F2")
    wait(lambda: tmux.log_shows("F2: RecordingProcessor.customize_processing(2) done"), 10, "F2 in the event log")
    tmux.keys("q")
    wait(tmux.status.exists, 15, "the exit status")
    assert tmux.status.read_text().strip() == "0"


FLIGHT = "arm\ntakeoff 3\nwait 6\nf 1\nautonomy on\n"
"""A --script that takes off and lets the steering test processor fly forward under autonomy."""


def fly(tmux: Tmux, tmp_path: Path, sim: SimVehicle, *flags: str) -> TruthClient:
    """Run the dashboard on ``sim`` with the steering processor flying it; returns once it flies."""
    (tmp_path / "steering.py").write_text(STEERING_PROCESSOR)
    (tmp_path / "flight.txt").write_text(FLIGHT)
    tmux.start("--fc", sim.connection_string, "--processor", "steering.py:Steering", "--script", "flight.txt",
               *flags, tmp_path=tmp_path)
    truth = sim.truth()
    wait(lambda: (s := truth.latest()) is not None and s.get("mode") == "OFFBOARD" and speed(s) > 0.3, 60,
         "uav-tui to fly the vehicle under autonomy")
    return truth


def held_after_exit(truth: TruthClient, exited_ns: int) -> None:
    """The vehicle holds and stops; nothing arrives from uav-tui after it exited."""
    assert truth.wait_latest()["mode"] == "HOLD"  # held by uav-tui itself before it exited
    wait(lambda: speed(truth.latest()) < 0.15, 5, "the vehicle to stop")
    time.sleep(0.5)
    assert truth.request({"cmd": "setpoints", "since_mono_ns": exited_ns})["records"] == []


@pytest.mark.parametrize("sim_vehicle", [NO_FAILSAFE], indirect=True)
def test_quit_while_flying_holds_the_vehicle_before_exit(tmux, tmp_path, sim_vehicle):
    truth = fly(tmux, tmp_path, sim_vehicle)
    tmux.keys("q")
    wait(lambda: "Quit?" in tmux.screen(), 10, "the quit confirmation")
    tmux.keys("y")
    wait(tmux.status.exists, 20, "the exit status")
    held_after_exit(truth, time.monotonic_ns())
    assert tmux.status.read_text().strip() == "0"


def processor_process(app: psutil.Process) -> psutil.Process:
    return next(p for p in app.children() if "uav_tui.hosting.child" in " ".join(p.cmdline()))


@pytest.mark.parametrize(("policy", "hangup"), [("stop", "close"), ("stop", "ssh"), ("continue", "close"),
                                                ("continue", "ssh")],
                         ids=["stop-terminal-closed", "stop-ssh-dropped", "continue-terminal-closed",
                              "continue-ssh-dropped"])
@pytest.mark.parametrize("sim_vehicle", [NO_FAILSAFE], indirect=True)
def test_hangup_stops_or_continues_headless(tmux, tmp_path, sim_vehicle, policy, hangup):
    truth = fly(tmux, tmp_path, sim_vehicle, "--on-hangup", policy)
    app = psutil.Process(tmux.app_pid())
    processor = processor_process(app)
    job = os.getpgid(app.pid)
    lost = time.monotonic_ns()
    tmux.kill()  # the terminal is gone; the shell in between swallows SIGHUP: only EIO tells
    if hangup == "ssh":  # a login shell whose SSH session dropped sends SIGHUP to every process of its job
        os.killpg(job, signal.SIGHUP)
    if policy == "continue":
        # Headless now, autonomy keeps flying: new vectors keep reaching the vehicle well after the hang-up.
        wait(lambda: any(r["vx"] > 0 and r["t_mono_ns"] > lost + 2e9 for r in
                         truth.request({"cmd": "setpoints", "since_mono_ns": lost})["records"]), 15,
             "vectors two seconds after the hang-up")
        assert app.is_running() and not tmux.status.exists()
        assert truth.latest()["mode"] == "OFFBOARD"
        assert processor_process(app).pid == processor.pid  # the same processor (its target) carries on
        assert app.cpu_percent(interval=1.0) < 50  # headless: not spinning on the dead terminal
        app.send_signal(signal.SIGTERM)
    wait(tmux.status.exists, 20, "the exit status")
    held_after_exit(truth, time.monotonic_ns())
    assert tmux.status.read_text().strip() == "0"


def test_a_stalled_terminal_never_blocks_the_platform(tmux, tmp_path, sim_vehicle):
    """An SSH connection stalled on bad Wi-Fi: the terminal takes no output (its tmux server is stopped) for 10 s.

    Telemetry keeps being handled on the loop (recorded without a gap); afterwards the screen is drawn again."""
    tmux.start("--fc", sim_vehicle.connection_string, "--record", tmp_path=tmp_path)
    wait(lambda: "proc Rec" in tmux.screen() and tmux.log_shows("first frame processed"), 30,
         "the dashboard with frames flowing")
    server = psutil.Process(int(tmux.tmux("display-message", "-p", "#{pid}").strip()))
    server.suspend()
    stalled = time.time_ns()
    time.sleep(10)
    server.resume()
    resumed = time.time_ns()
    wait(lambda: re.search(r"proc +[1-9]", tmux.screen()), 10, "the dashboard after the stall")
    tmux.keys("q")
    wait(tmux.status.exists, 15, "the exit status")
    assert tmux.status.read_text().strip() == "0"
    (run,) = (tmp_path / "runs").iterdir()
    with (run / "telemetry.csv").open() as rows:
        stamps = [int(row["t_wall_ns"]) for row in csv.DictReader(rows) if stalled <= int(row["t_wall_ns"]) <= resumed]
    assert stamps and stamps[0] - stalled < 1e9 and resumed - stamps[-1] < 1e9
    assert max(b - a for a, b in itertools.pairwise(stamps)) < 1e9  # the loop never stopped (it did for ~5 s)


@pytest.mark.parametrize(("lines", "status"), [("f 3\nwait 30\n", "0"), ("f 3\nroi 9000 0 5 5\nwait 30\n", "1")],
                         ids=["duration-ends-the-run", "failed-script-line-ends-it"])
def test_script_and_duration_run_with_the_dashboard(tmux, tmp_path, lines, status):
    script = tmp_path / "mission.txt"
    script.write_text(lines)
    tmux.start("--fc", "none", "--script", str(script), "--duration", "4", tmp_path=tmp_path)
    if status == "0":  # (a failing script ends the run at once, too fast to read the screen)
        wait(lambda: tmux.log_shows("F3: RecordingProcessor.customize_processing(3) done"), 30,
             "the script's F3 in the event log")
    wait(tmux.status.exists, 30, "the run to end by itself")
    assert tmux.status.read_text().strip() == status


def test_a_finished_script_leaves_the_dashboard_to_the_operator(tmux, tmp_path):
    script = tmp_path / "mission.txt"
    script.write_text("f 3\n")
    tmux.start("--fc", "none", "--script", str(script), tmp_path=tmp_path)
    wait(lambda: tmux.log_shows("script finished"), 30, "the end of the script in the event log")
    time.sleep(1)
    assert not tmux.status.exists()  # still running
    tmux.keys("q")
    wait(tmux.status.exists, 15, "the exit status")
    assert tmux.status.read_text().strip() == "0"


def test_a_damaged_real_video_leaves_the_screen_whole(tmux, tmp_path):
    video = damaged_aerial_video(tmp_path)
    tmux.start("--fc", "none", "--source", f"file:{video}", tmp_path=tmp_path)
    wait(lambda: tmux.log_shows("native library: [mpeg4 @ 0x"), 30, "FFmpeg's complaint in the event log")
    lines = tmux.screen().splitlines()
    # Before: FFmpeg wrote over the panels, the preview and the key bar, and the log never had it.
    assert not any("mpeg4" in line[:LOG_COLUMN] for line in lines), lines
    assert lines[-1].rstrip().endswith("q Quit  ? Help") and "Preview" in lines[2], lines
    tmux.keys("q")
    wait(tmux.status.exists, 15, "the exit status")
    assert tmux.status.read_text().strip() == "0"


def test_what_the_processor_prints_in_its_own_process_shows_in_the_log(tmux, tmp_path):
    tmux.start("--fc", "none", "--processor", f"{ROOT / 'tests/tui/procs.py'}:PrintingProcessor", tmp_path=tmp_path)
    # Before: lost, with nothing on the screen.
    wait(lambda: tmux.log_shows("print: hello from the processor, frame 60"), 30, "the processor's print in the log")
    tmux.keys("q")
    wait(tmux.status.exists, 15, "the exit status")
    assert tmux.status.read_text().strip() == "0"


@pytest.mark.parametrize(("colorterm", "truecolor"), [("", False), ("truecolor", True)],
                         ids=["256-colours", "truecolor"])
def test_colours_follow_what_the_terminal_says_it_can_do(tmux, tmp_path, colorterm, truecolor):
    tmux.start("--fc", "none", tmp_path=tmp_path, colorterm=colorterm)
    wait(lambda: "proc Rec" in tmux.screen() and tmux.log_shows("started"), 30, "the dashboard")
    time.sleep(1)  # a few preview frames
    screen = tmux.screen(escapes=True)
    assert ("\x1b[38;2;" in screen or ";38;2;" in screen) is truecolor  # 24-bit colours only when announced
    assert "38;5;" in screen or truecolor  # otherwise the 256-colour palette
    tmux.keys("q")
    wait(tmux.status.exists, 15, "the exit status")
