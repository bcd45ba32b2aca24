"""``uav-tui --no-ui`` as a user runs it: a real process, real output, real exit codes."""

from __future__ import annotations

import asyncio
import contextlib
import csv
import fcntl
import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import psutil
import pytest

from controllers.sim.launcher import free_ports
from tests.videos import damaged_aerial_video
from uav_tui import headless
from uav_tui.config import load_config
from uav_tui.core import CoreState

ROOT = Path(__file__).resolve().parents[2]

CHATTY_PROCESSOR = """
class Chatty:
    def __init__(self):
        self.tmMgr = None

    def photo_processing(self, frame):
        print("a researcher's debugging line " + "." * 4000)  # 120 KB/s: the pipe from its process fills in 1 s
"""


def uav(*args: str, cwd: Path, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "uav_tui", *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=timeout)


def test_headless_run_prints_stats_and_exits_zero(tmp_path: Path) -> None:
    result = uav("--no-ui", "--duration", "3", "--source", "synthetic:", "--processor", "template",
                 "--runs-dir", str(tmp_path / "runs"), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    lines = [line for line in result.stdout.splitlines() if "fps proc " in line]  # the status lines
    assert len(lines) >= 2
    assert "stopped: --duration 3 s reached" in result.stdout
    fps = float(lines[-1].split("proc")[1].split("fps")[0])
    assert fps > 0  # frames are processed (how fast is scripts/bench_pipeline.py's question)


def test_json_lines(tmp_path: Path) -> None:
    result = uav("--no-ui", "--json", "--duration", "2.5", "--runs-dir", str(tmp_path / "runs"), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    records = [json.loads(line) for line in result.stdout.splitlines()]  # every line, to the last
    assert records[-2] == {"stopped": "--duration 2.5 s reached"} and "run_dir" in records[-1]
    status = [r for r in records if "pipeline" in r]
    assert status and status[-1]["processor"] == "processors.template:MeanBrightnessProcessor"
    assert status[-1]["pipeline"]["frames_processed"] > 10


def test_json_lines_stay_json_when_the_processor_prints(tmp_path: Path) -> None:
    (tmp_path / "chatty.py").write_text(CHATTY_PROCESSOR)
    result = uav("--no-ui", "--json", "--duration", "2", "--no-record", "--processor", "chatty.py:Chatty", cwd=tmp_path)
    assert result.returncode == 0, result.stderr[-2000:]
    records = [json.loads(line) for line in result.stdout.splitlines()]
    assert records[-1] == {"stopped": "--duration 2 s reached"}
    assert "a researcher's debugging line ..." in result.stderr  # its prints go to stderr


def test_config_error_names_the_key_and_exits_2(tmp_path: Path) -> None:
    (tmp_path / "uav.toml").write_text("[safety]\nmax_speed = 50\n")
    result = uav("--no-ui", "--duration", "1", cwd=tmp_path)
    assert result.returncode == 2
    assert "safety.max_speed" in result.stderr and "out of range" in result.stderr


def test_processor_import_error_says_file_line_and_what_is_missing(tmp_path: Path) -> None:
    (tmp_path / "mine.py").write_text("import numpy\nimport missing_dependency\n")
    result = uav("--no-ui", "--duration", "1", "--processor", "mine.py:Mine", cwd=tmp_path)
    assert result.returncode == 2
    assert result.stderr.startswith("uav-tui: error: ") and "mine.py:2" in result.stderr
    assert "missing_dependency" in result.stderr


def test_a_vehicle_that_never_answers_is_one_clear_line_and_nothing_left_running(tmp_path: Path) -> None:
    (port,) = free_ports(1)
    result = uav("--no-ui", "--duration", "1", "--fc", f"udpin://127.0.0.1:{port}", "--connect-timeout", "1",
                 cwd=tmp_path)
    assert result.returncode == 2
    # Before: a warning about "MAVSDK calls still blocked: Popen.wait" followed (the processor's process reaped
    # through the loop's executor after the loop had ended).
    assert result.stderr.splitlines() == [
        f"uav-tui: error: no heartbeat on udpin://127.0.0.1:{port} within 1 s: check wiring / baud / port / that "
        "the autopilot sends to this port (PX4 SITL sends to udpin://0.0.0.0:14540)"], result.stderr
    left = [p for p in psutil.process_iter(["cwd"]) if p.info["cwd"] == str(tmp_path)]
    assert left == []  # the processor's process started while connecting is gone too


def test_a_camera_that_cannot_open_is_one_clear_line(tmp_path: Path) -> None:
    result = uav("--no-ui", "--duration", "1", "--source", "file:flight.mp4", cwd=tmp_path)
    assert result.returncode == 2
    # Before: the source's own warning said the same first.
    assert result.stderr.splitlines() == [
        f"uav-tui: error: cannot open camera 'file:flight.mp4': no such video file: flight.mp4 (working "
        f"directory: {tmp_path})"], result.stderr


def test_a_damaged_real_video_is_reported_in_events_not_sprayed_on_the_terminal(tmp_path: Path) -> None:
    video = damaged_aerial_video(tmp_path)
    result = uav("--no-ui", "--duration", "9", "--fc", "none", "--source", f"file:{video}", "--runs-dir",
                 str(tmp_path / "runs"), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    # Before: FFmpeg's raw lines on stderr, in no record of the run.
    assert "[mpeg4 @" not in result.stderr, result.stderr
    printed = re.findall(r"^\[\w+\] platform: native library: .+$", result.stdout, re.MULTILINE)
    assert any(re.match(r"\[warning\] platform: native library: \[mpeg4 @ 0x\w+\] .", line) for line in printed), \
        result.stdout
    with open(next((tmp_path / "runs").iterdir()) / "events.csv", newline="") as file:
        recorded = [row for row in csv.DictReader(file) if row["origin"] == "native"]
    assert [f"[{row['level']}] {row['kind']}: {row['message']}" for row in recorded] == printed


def test_a_run_started_without_stderr_runs(tmp_path: Path) -> None:
    # As some launchers start it (2>&-): fd 2 is then whatever the process opens next (the event loop's
    # selector, say), which capturing native stderr must not take over.
    command = [sys.executable, "-m", "uav_tui", "--no-ui", "--fc", "none", "--source", "synthetic:", "--duration",
               "2", "--runs-dir", str(tmp_path / "runs")]
    result = subprocess.run(["sh", "-c", 'exec "$@" 2>&-', "sh", *command], cwd=tmp_path, capture_output=True,
                            text=True, timeout=60, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert result.returncode == 0, result.stdout
    assert "stopped: --duration 2 s reached" in result.stdout


def test_vehicle_command_without_a_vehicle_fails_the_script_clearly(tmp_path: Path) -> None:
    (tmp_path / "flight.txt").write_text("f 1\narm\n")
    (tmp_path / "mine.py").write_text("class Mine:\n    def photo_processing(self, frame):\n        pass\n"
                                      "    def customize_processing(self, id):\n        print('button', id)\n")
    result = uav("--no-ui", "--fc", "none", "--processor", "mine.py:Mine", "--script", "flight.txt",
                 "--runs-dir", str(tmp_path / "runs"), cwd=tmp_path)
    assert result.returncode == 1
    assert "button 1" in result.stdout
    assert result.stderr.startswith("uav-tui: error: script line 2 (arm) failed") and "--fc sim" in result.stderr


@contextlib.contextmanager
def headless_job(tmp_path: Path, *flags: str) -> Iterator[subprocess.Popen[str]]:
    """``uav-tui --no-ui`` as a job of its own (as a shell starts it), once its first status line is out. However
    the test ends (a pytest-timeout included) it is killed, reaped and its pipes closed: left to the garbage
    collector, they failed a later test of the same worker with ResourceWarning."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    with subprocess.Popen([sys.executable, "-m", "uav_tui", "--no-ui", "--runs-dir", str(tmp_path / "runs"), *flags],
                          cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                          process_group=0) as process:  # a job, in the shell's session; leaving: pipes closed, reaped
        try:
            assert process.stdout is not None
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline and process.poll() is None:
                if "fps proc " in process.stdout.readline():  # a status line: the loop is running
                    yield process
                    return
            process.kill()
            pytest.fail(f"no status line: {process.communicate()}")
        finally:
            process.kill()


@pytest.mark.parametrize(("signum", "to_job"), [(signal.SIGTERM, False), (signal.SIGINT, True), (signal.SIGHUP, True)],
                         ids=["TERM", "INT-Ctrl-C", "HUP-ssh-dropped"])
def test_signals_stop_cleanly(tmp_path: Path, signum: int, to_job: bool) -> None:
    """A terminal sends Ctrl-C, and a login shell whose SSH session dropped SIGHUP, to every process of the job:
    the platform stops in order; its helpers (the processor's process, the shared-memory tracker) are not hit."""
    with headless_job(tmp_path) as process:
        if to_job:
            os.killpg(process.pid, signum)
        else:
            process.send_signal(signum)
        out, err = process.communicate(timeout=20)
    assert process.returncode == 0, err
    assert "stopped:" in out
    assert "processor (pid" not in out + err  # no crash of the processor's process reported
    assert "resource_tracker" not in err  # it did not die ("process died unexpectedly, relaunching")


def test_ctrl_z_does_not_suspend_a_headless_run(tmp_path: Path) -> None:
    """Suspended, the platform would stop streaming to the vehicle: Ctrl-Z (SIGTSTP to the job) is refused, said."""
    with headless_job(tmp_path) as process:
        try:
            assert process.stdout is not None
            os.killpg(process.pid, signal.SIGTSTP)
            time.sleep(1.0)
            assert psutil.Process(process.pid).status() != psutil.STATUS_STOPPED
            lines = [process.stdout.readline() for _ in range(3)]  # status lines go on
            process.send_signal(signal.SIGTERM)
            out, err = process.communicate(timeout=20)
        finally:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(process.pid, signal.SIGCONT)  # wakes the job's other processes, were they stopped
    assert process.returncode == 0, err
    assert "[warning] platform: Ctrl-Z ignored: a suspended uav-tui would stop flying the vehicle" in "".join(lines)
    assert "processor (pid" not in out + err and "stopped: SIGTERM" in out


def test_hangup_with_continue_keeps_the_run_and_its_processor_going(tmp_path: Path) -> None:
    with headless_job(tmp_path, "--on-hangup", "continue") as process:
        assert process.stdout is not None
        processor = next(p for p in psutil.Process(process.pid).children() if "uav_tui.hosting.child" in p.cmdline())
        os.killpg(process.pid, signal.SIGHUP)  # the SSH session dropped
        lines = [process.stdout.readline() for _ in range(3)]  # status lines go on
        assert processor.is_running() and process.poll() is None
        process.send_signal(signal.SIGTERM)
        out, err = process.communicate(timeout=20)
    assert process.returncode == 0, err
    assert "[warning] platform: terminal lost (SIGHUP), --on-hangup continue: the run goes on" in "".join(lines) + out
    assert "processor (pid" not in out + err and "stopped: SIGTERM" in out


@pytest.mark.parametrize(("option", "name", "content"), [
    ("--config", "uav.toml", "[safety]\nmax_speed = 0.5 # caf\xe9\n".encode("latin-1")),
    ("--script", "flight.txt", b"arm\n\xff\xfe takeoff\n"),
], ids=["config", "script"])
def test_a_file_that_is_not_utf8_is_a_clear_error(tmp_path: Path, option: str, name: str, content: bytes) -> None:
    (tmp_path / name).write_bytes(content)
    result = uav("--no-ui", "--duration", "1", option, name, cwd=tmp_path)
    assert result.returncode == 2
    assert f"{name} is not UTF-8" in result.stderr or f"{name}: not UTF-8" in result.stderr
    assert "Traceback" not in result.stderr and "UnicodeDecodeError" not in result.stderr


@pytest.mark.parametrize("line", ["roi inf 0 1 1", "takeoff 10000"])
def test_a_script_with_an_impossible_value_exits_2_before_starting(tmp_path: Path, line: str) -> None:
    (tmp_path / "flight.txt").write_text(f"f 1\n{line}\n")
    result = uav("--no-ui", "--duration", "5", "--script", "flight.txt", "--runs-dir", str(tmp_path / "runs"),
                 cwd=tmp_path)
    assert result.returncode == 2
    assert "flight.txt:2" in result.stderr and "Traceback" not in result.stderr
    assert not (tmp_path / "runs").exists()  # nothing started


def test_log_records_reach_the_terminal_escaped(tmp_path: Path) -> None:
    """The real logging setup of ``uav-tui``: a processor's string with escapes and a newline stays one line."""
    (tmp_path / "noisy.py").write_text(
        "import logging\n"
        "class Noisy:\n"
        "    def photo_processing(self, frame):\n"
        "        logging.getLogger('noisy').warning('seen \\x1b[2J\\n[info] command: arm rtsp://a:Hunter2pw@h/')\n")
    result = uav("--no-ui", "--duration", "1.5", "--processor", "noisy.py:Noisy", "--no-record", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "seen \\x1b[2J\\n[info] command: arm rtsp://a:***@h/" in result.stderr
    assert "\x1b" not in result.stderr and "Hunter2pw" not in result.stderr
    assert not any(line.startswith("[info] command: arm") for line in result.stderr.splitlines())


async def test_a_stalled_terminal_never_blocks_a_headless_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """An SSH connection stalled on bad Wi-Fi stops reading: ``--no-ui``'s lines (and the processor's prints) wait,
    then are dropped and that is said once the terminal takes output again; the event loop (the vehicle's link, the
    hold) never waits, and neither does the processor."""
    monkeypatch.setattr(headless, "OUTPUT_BACKLOG_CHARS", 2000)  # a few of the processor's lines: drops at once
    read_fd, write_fd = os.pipe()
    fcntl.fcntl(write_fd, fcntl.F_SETPIPE_SZ, 4096)  # the terminal's buffer, full after a few status lines
    out = os.fdopen(write_fd, "w")
    (tmp_path / "chatty.py").write_text(CHATTY_PROCESSOR)
    config = load_config(None, {"fc": "sim", "source": "synthetic:?width=160&height=120", "record": False,
                                "processor": f"{tmp_path / 'chatty.py'}:Chatty"})
    runner = headless.HeadlessRunner(config, duration=9.0, out=out)
    gaps: list[tuple[float, float]] = []  # (time, the loop's lag before it)
    processed: list[tuple[float, int]] = []  # (time, frames processed)
    running = threading.Event()

    async def tick() -> None:  # the loop's own lag: a blocked print would show as a gap of seconds
        last = time.monotonic()
        while True:
            await asyncio.sleep(0.02)
            gaps.append((time.monotonic(), time.monotonic() - last))
            last = time.monotonic()
            if runner.core.state is CoreState.RUNNING:
                running.set()
                processed.append((last, runner.core.worker.snapshot().frames_processed))

    received: list[bytes] = []

    def read_after_the_stall() -> None:
        running.wait(30)
        time.sleep(6.0)  # nothing reads for 6 s of the run
        while chunk := os.read(read_fd, 1 << 16):
            received.append(chunk)

    reader = threading.Thread(target=read_after_the_stall)
    reader.start()
    ticker = asyncio.create_task(tick())
    try:
        assert await asyncio.wait_for(runner.run(), 40) == headless.EXIT_OK
    finally:
        ticker.cancel()
        out.close()
        reader.join(10)
        os.close(read_fd)
    stalled_from = processed[0][0]
    # Blocked by the terminal, the loop would wait out the 6 s stall; a loaded machine's scheduler gives it some
    # tenths of a second now and then (0.6 s at load 6 on 2 cores), so the bound is a third of the stall.
    waited = max(gap for t, gap in gaps if stalled_from <= t <= stalled_from + 6)
    assert waited < 2.0, f"the loop waited {waited:.2f} s while the terminal stalled"
    during = [count for t, count in processed if stalled_from + 2 <= t <= stalled_from + 5]
    assert during[-1] - during[0] > 3 * 15, processed  # the processor kept its 30 FPS (a blocked one: none)
    lines = b"".join(received).decode().splitlines()
    assert any(re.fullmatch(r"\[warning\] platform: \d+ lines of output were dropped while the terminal was not "
                            r"taking them \(events.csv has every event\)", line) for line in lines), lines[-20:]
    assert lines[-1] == "stopped: --duration 9 s reached"  # the end, after the stall, is not lost
