"""CPU cost of the dashboard: processed FPS and process CPU with the TUI on (in a real terminal, tmux) vs --no-ui.

Both modes run ``python -m uav_tui`` on the same input with the same processor, :class:`CountingProcessor`
(defined here, loaded by file path), which does a few milliseconds of OpenCV work per frame and, at exit,
writes how many frames it processed in the measuring window and the process's CPU time. Two inputs:
``synthetic:?realtime=0`` (frames as fast as they come: the processor is CPU-bound, so any CPU the UI
takes shows up as lost FPS) and a 30 FPS camera (FPS should match; the CPU difference is the UI's cost).
Prints one JSON object; the goal is ``fps_ratio >= 0.95`` (UI FPS / headless FPS).

    python scripts/bench_ui.py [--seconds 10] [--repeat 3] [--sizes 80x24,160x48]
"""

from __future__ import annotations

import argparse
import atexit
import json
import os
import resource
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2

ROOT = Path(__file__).resolve().parents[1]
INPUTS = {"unpaced": "synthetic:?realtime=0", "camera_30fps": "synthetic:?fps=30"}
"""Frames as fast as the machine makes them (CPU-bound), and a 30 FPS camera."""

WARMUP_S = 2.0
"""Frames in the first seconds after the first frame are not counted (imports, start-up, first layout)."""


class CountingProcessor:
    """Blur + edges per frame (a few ms at 640x480); writes its counts to $BENCH_UI_OUT at exit."""

    def __init__(self) -> None:
        self.tmMgr = None
        self.times: list[float] = []
        self.created, self.cpu_at_start = time.monotonic(), _cpu_s()
        atexit.register(self._report)

    def photo_processing(self, frame):  # noqa: ANN001, ANN201 - the researcher's contract is untyped
        edges = cv2.Canny(cv2.GaussianBlur(frame, (7, 7), 0), 50, 150)
        self.edges = int(edges[::16, ::16].sum())
        self.times.append(time.monotonic())

    def _report(self) -> None:
        start = self.times[0] + WARMUP_S if self.times else 0.0
        counted = [t for t in self.times if t >= start]
        span = counted[-1] - counted[0] if len(counted) > 1 else 0.0
        # CPU of the whole process (every thread) from the processor's creation to the exit, per second.
        cpu_cores = (_cpu_s() - self.cpu_at_start) / (time.monotonic() - self.created)
        result = {"fps": (len(counted) - 1) / span if span else 0.0, "frames": len(self.times), "cpu_cores": cpu_cores}
        Path(os.environ["BENCH_UI_OUT"]).write_text(json.dumps(result))


def _cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def run(mode: str, source: str, seconds: float, workdir: Path) -> dict[str, float]:
    """Run uav-tui once (``mode`` = ``headless`` or ``WxH`` for the TUI in tmux) and read the processor's report."""
    out = workdir / f"{mode}-{abs(hash(source))}.json"
    out.unlink(missing_ok=True)
    command = [sys.executable, "-m", "uav_tui", "--fc", "none", "--source", source, "--no-record",
               "--runs-dir", str(workdir / "runs"), "--processor", f"{Path(__file__).resolve()}:CountingProcessor",
               "--duration", str(seconds),
               # In the platform's process: its report is that process's CPU, the UI's included (a processor in a
               # child process measures only itself, and is killed at the stop before it can report).
               "--isolation", "thread"]
    env = {**os.environ, "PYTHONPATH": str(ROOT), "BENCH_UI_OUT": str(out)}
    started = time.monotonic()
    if mode == "headless":
        # Not check=True: an OpenCV call still running on the processor thread at interpreter exit can
        # abort the process after the report was written (a core issue, reported); the report is what counts.
        subprocess.run([*command, "--no-ui"], env=env, cwd=workdir, stdout=subprocess.DEVNULL, timeout=seconds + 60)
    else:
        width, height = mode.split("x")
        socket = str(workdir / f"tmux-{time.monotonic_ns()}.sock")  # a fresh server per run, removed with workdir
        shell = " ".join(f"{k}={shlex.quote(v)}" for k, v in env.items() if k in ("PYTHONPATH", "BENCH_UI_OUT"))
        subprocess.run(["tmux", "-S", socket, "new-session", "-d", "-x", width, "-y", height,
                        f"cd {shlex.quote(str(workdir))} && env {shell} TERM=xterm-256color {shlex.join(command)}"],
                       check=True, timeout=10)
        try:
            while not out.exists() and time.monotonic() - started < seconds + 60:
                time.sleep(0.2)
        finally:
            subprocess.run(["tmux", "-S", socket, "kill-server"], capture_output=True, timeout=10)
    while not out.exists() and time.monotonic() - started < seconds + 60:
        time.sleep(0.1)
    result = json.loads(out.read_text())
    return {"fps": round(result["fps"], 1), "frames": result["frames"], "cpu_cores": round(result["cpu_cores"], 2)}


def median_run(mode: str, source: str, seconds: float, workdir: Path, repeat: int) -> dict[str, float]:
    """The run with the median FPS of ``repeat`` runs (the machine may be shared: single runs are noisy)."""
    runs = sorted((run(mode, source, seconds, workdir) for _ in range(repeat)), key=lambda r: r["fps"])
    return {**runs[len(runs) // 2], "fps_all": [r["fps"] for r in runs]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="length of each run")
    parser.add_argument("--repeat", type=int, default=3, help="runs per mode; the median is reported")
    parser.add_argument("--sizes", default="80x24,160x48", help="terminal sizes for the TUI runs")
    parser.add_argument("--inputs", default="unpaced,camera_30fps", help="which inputs to run")
    args = parser.parse_args()
    if shutil.which("tmux") is None:
        sys.exit("bench_ui needs tmux (the TUI runs in a real terminal)")
    sizes = args.sizes.split(",")
    inputs = {name: source for name, source in INPUTS.items() if name in args.inputs.split(",")}
    report: dict[str, object] = {"seconds": args.seconds, "repeat": args.repeat, "cpus": os.cpu_count(),
                                 "load_avg_1min": round(os.getloadavg()[0], 2), "inputs": inputs}
    ratios = []
    with tempfile.TemporaryDirectory(prefix="bench-ui-") as tmp:
        workdir = Path(tmp)
        for name, source in inputs.items():
            headless = median_run("headless", source, args.seconds, workdir, args.repeat)
            entry: dict[str, object] = {"headless": headless}
            for size in sizes:
                ui = median_run(size, source, args.seconds, workdir, args.repeat)
                ui["fps_ratio"] = round(ui["fps"] / headless["fps"], 3) if headless["fps"] else 0.0
                ui["extra_cpu_cores"] = round(ui["cpu_cores"] - headless["cpu_cores"], 2)
                ratios.append(ui["fps_ratio"])
                entry[f"tui_{size}"] = ui
            report[name] = entry
    report["min_fps_ratio"] = min(ratios)
    report["goal_met"] = min(ratios) >= 0.95
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
