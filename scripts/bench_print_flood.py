"""A processor that prints a flood: processed FPS and the platform's memory, dashboard (tmux) and --no-ui.

The processor (:class:`Printer`, defined here, loaded by file path, in its own process) prints ``--kb`` KB a
frame in 100-character lines (``--no-newline``: one line that never ends) at a 30 FPS camera; a quiet run
(the same processor printing as much into /dev/null: what printing costs the processor itself) is the
reference, so the ratio is what taking the output costs. Processed FPS comes from the run's ``frames.csv``
(frames after the first 2 s), memory from the uav-tui process's RSS (psutil) at 40 % and 90 % of the run.
Issue 42 measured the dashboard at 3-8 FPS (from 30) and the platform growing ~40 MB/s without newlines.
Prints one JSON object; the goal is ``fps_ratio >= 0.9`` (flood / quiet) and ``rss_growth_mb < 20``.
With ``--web``, headless runs also serve the web page, and a client sends its ``autonomy off`` command
(``POST /api/command``) 10 times a second over the measured half of the run: ``command_ms`` is the latency
(p50/p95/max; issue 42 measured p95 4 ms quiet and 61 ms in a flood).

    python scripts/bench_print_flood.py [--seconds 15] [--kb 1000] [--no-newline] [--modes headless,120x40] [--web]
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import secrets
import shlex
import shutil
import socket as sockets
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path
from typing import Any

import psutil

ROOT = Path(__file__).resolve().parents[1]
SOURCE = "synthetic:?width=320&height=240&fps=30"
WARMUP_S = 2.0


class Printer:
    """Prints ``kb`` KB a frame in 100-character lines, or one line that never ends; into /dev/null if ``quiet``."""

    def __init__(self, kb: int = 0, newline: bool = True, quiet: bool = False) -> None:
        self.lines, self.end = kb * 10, "\n" if newline else ""
        self.file = open(os.devnull, "w") if quiet else None  # noqa: SIM115 - for the process's life

    def photo_processing(self, frame):  # noqa: ANN001, ANN201 - the researcher's contract is untyped
        for _ in range(self.lines):
            print("x" * 99, end=self.end, file=self.file)


def run(mode: str, kb: int, newline: bool, quiet: bool, seconds: float, workdir: Path,
        web: bool = False) -> dict[str, Any]:
    """One run of uav-tui (``headless``, or ``WxH``: the dashboard in tmux); its processed FPS and RSS growth, and with
    ``web`` (headless) the web page's command latency."""
    runs = workdir / f"runs-{time.monotonic_ns()}"
    command = [sys.executable, "-m", "uav_tui", "--fc", "none", "--source", SOURCE, "--runs-dir", str(runs),
               "--no-record-video", "--processor", f"{Path(__file__).resolve()}:Printer", "--processor-arg",
               f"kb={kb}", "--processor-arg", f"newline={str(newline).lower()}", "--processor-arg",
               f"quiet={str(quiet).lower()}", "--duration", str(seconds)]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    page = _web_page() if web and mode == "headless" else None
    if page is not None:
        command += ["--web", "--web-host", "127.0.0.1", "--web-port", str(page[0]), "--web-token", page[1]]
    if mode == "headless":
        proc = subprocess.Popen([*command, "--no-ui"], env=env, cwd=workdir, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
        platform, wait = psutil.Process(proc.pid), proc.wait
    else:
        width, height = mode.split("x")
        socket = str(workdir / f"tmux-{time.monotonic_ns()}.sock")
        subprocess.run(["tmux", "-S", socket, "new-session", "-d", "-x", width, "-y", height,
                        f"cd {shlex.quote(str(workdir))} && PYTHONPATH={shlex.quote(str(ROOT))} TERM=xterm-256color "
                        f"exec {shlex.join(command)}"], check=True, timeout=10, env=env)
        pane = int(subprocess.run(["tmux", "-S", socket, "display", "-p", "#{pane_pid}"], capture_output=True,
                                  text=True, check=True).stdout)
        platform = psutil.Process(pane)

        def wait(timeout: float | None = None) -> None:
            with_deadline = time.monotonic() + (timeout or seconds + 60)
            while platform.is_running() and platform.status() != psutil.STATUS_ZOMBIE:
                if time.monotonic() > with_deadline:
                    raise TimeoutError(mode)
                time.sleep(0.2)
            subprocess.run(["tmux", "-S", socket, "kill-server"], capture_output=True, timeout=10)
    time.sleep(seconds * 0.4)  # start-up (a few seconds on a loaded machine), then the flood for a while
    if page is not None:
        _wait_for_page(page[0])
    rss = [platform.memory_info().rss / 2**20]
    latencies: list[float] = []
    if page is not None:
        latencies = _command_latencies(*page, seconds * 0.5)
    else:
        time.sleep(seconds * 0.5)
    rss.append(platform.memory_info().rss / 2**20)
    wait(seconds + 60)
    with open(next(runs.iterdir()) / "frames.csv", newline="") as rows:
        starts = sorted(int(row["t_start_ns"]) for row in csv.DictReader(rows))
    counted = [t for t in starts if t >= starts[0] + WARMUP_S * 1e9]
    fps = (len(counted) - 1) / ((counted[-1] - counted[0]) / 1e9) if len(counted) > 1 else 0.0
    result: dict[str, Any] = {"fps": round(fps, 1), "rss_mb": round(rss[0], 1),
                                 "rss_growth_mb": round(rss[1] - rss[0], 1)}
    if latencies:
        result["command_ms"] = {"n": len(latencies), "p50": round(statistics.median(latencies), 1),
                                "p95": round(statistics.quantiles(latencies, n=20)[18], 1),
                                "max": round(max(latencies), 1)}
    return result


def _web_page() -> tuple[int, str]:
    """A free loopback port and a random token for the web page."""
    with sockets.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    return port, secrets.token_urlsafe(24)


def _wait_for_page(port: int, timeout_s: float = 60.0) -> None:
    """Until the web page accepts connections (it starts after the processor and the camera)."""
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            with sockets.create_connection(("127.0.0.1", port), timeout=1):
                return
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)


def _command_latencies(port: int, token: str, seconds: float) -> list[float]:
    """Milliseconds each ``autonomy off`` took through the web page, sent 10 times a second for ``seconds``."""
    request = urllib.request.Request(f"http://127.0.0.1:{port}/api/command", method="POST",
                                     data=json.dumps({"command": "autonomy off"}).encode(),
                                     headers={"Authorization": f"Bearer {token}", "Content-Type": "application/json"})
    latencies: list[float] = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        start = time.perf_counter()
        with urllib.request.urlopen(request, timeout=10) as response:
            response.read()
        latencies.append((time.perf_counter() - start) * 1000)
        time.sleep(0.1)
    return latencies


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=15.0, help="length of each run")
    parser.add_argument("--kb", type=int, default=1000, help="KB printed a frame")
    parser.add_argument("--no-newline", action="store_true", help="print one line that never ends")
    parser.add_argument("--modes", default="headless,120x40", help="headless and/or WxH terminal sizes (tmux)")
    parser.add_argument("--web", action="store_true", help="headless runs: measure the web page's command latency")
    args = parser.parse_args()
    modes = args.modes.split(",")
    if any(mode != "headless" for mode in modes) and shutil.which("tmux") is None:
        sys.exit("the dashboard runs need tmux")
    report: dict[str, object] = {"seconds": args.seconds, "kb_per_frame": args.kb, "newline": not args.no_newline,
                                 "source": SOURCE, "cpus": os.cpu_count(),
                                 "load_avg_1min": round(os.getloadavg()[0], 2)}
    ratios, growth = [], []
    with tempfile.TemporaryDirectory(prefix="bench-print-") as tmp:
        for mode in modes:
            quiet = run(mode, args.kb, not args.no_newline, True, args.seconds, Path(tmp), args.web)
            flood = run(mode, args.kb, not args.no_newline, False, args.seconds, Path(tmp), args.web)
            flood["fps_ratio"] = round(flood["fps"] / quiet["fps"], 3) if quiet["fps"] else 0.0
            ratios.append(flood["fps_ratio"])
            growth.append(flood["rss_growth_mb"])
            report[mode] = {"quiet": quiet, "flood": flood}
    report["goal_met"] = min(ratios) >= 0.9 and max(growth) < 20
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
