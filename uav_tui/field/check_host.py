"""``doctor``'s checks of the computer: its clock, the disk runs are recorded on, the shipped models, the CPU's
governor and throttling, and the web page's token."""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

from uav_tui.config import Config
from uav_tui.field.finding import Finding, fail, ok, warn
from uav_tui.field.tools import run_tool
from uav_tui.flight.clock_check import CLOCK_OFF_S, clock_advice
from uav_tui.token_strength import MIN_TOKEN_BITS, token_bits, token_problem

GOVERNOR = Path("/sys/devices/system/cpu/cpu0/cpufreq/scaling_governor")
LOW_DISK_FACTOR = 10
"""Less free space than this many times ``min_free_mb`` is a warning (a long flight fills it)."""
UNDER_VOLTAGE_NOW = 0x1
THROTTLE_NOW = 0x2 | 0x4 | 0x8
"""``vcgencmd get_throttled`` bits: under-voltage now; frequency capped, throttled or at the soft temperature limit
now. The same four shifted by 16 say it happened since boot."""
LFS_POINTER = b"version https://git-lfs"


def clock(gps_offset_ms: int | None) -> Finding:
    """Network time, or failing that the autopilot's GPS time, says whether this computer's clock is right."""
    done, output = run_tool("timedatectl", "show", "--property=NTPSynchronized", "--value")
    if done and output.strip() == "yes":
        return ok("clock", "synchronised with network time")
    if gps_offset_ms is not None:
        advice = clock_advice(gps_offset_ms)
        if advice:
            return warn("clock", advice)
        return ok("clock", f"no network time, but within {CLOCK_OFF_S:g} s of the autopilot's GPS time")
    return warn("clock", "no network time and no GPS time to compare with: the clock may be hours behind (run "
                         "folder names and t_wall_ns use it); get a GPS fix and run doctor again, or set it with "
                         "sudo date -s")


def disk(config: Config, usage: Callable[[Path], Any] = shutil.disk_usage) -> Finding:
    """Free space where runs are recorded against ``min_free_mb`` (below it the recorder stops saving frames)."""
    recording = config.recording
    if not recording.record:
        return ok("disk", "recording is off (record = false)")
    folder = Path(recording.runs_dir).expanduser().absolute()
    existing = next(p for p in (folder, *folder.parents) if p.exists())
    free_mb = usage(existing).free / 1e6
    text = f"{free_mb:,.0f} MB free for {folder}"
    if free_mb < recording.min_free_mb:
        return fail("disk", f"{text}, below min_free_mb = {recording.min_free_mb:g}: the recorder would save no "
                            "frames; delete old runs (uav-tui runs lists them) or set runs_dir to a bigger disk")
    if free_mb < recording.min_free_mb * LOW_DISK_FACTOR:
        return warn("disk", f"{text}: little room above min_free_mb = {recording.min_free_mb:g}; "
                            "delete old runs (uav-tui runs lists them)")
    return ok("disk", text)


def models() -> list[Finding]:
    """The models shipped as package data: present and real (not a Git LFS pointer left by a clone without LFS)."""
    from processors import models as shipped

    files = [Path(path) for path in shipped.nanotrack_files().values()]
    files += sorted(p for p in shipped.YOLO_FASTEST.iterdir() if p.suffix in (".cfg", ".weights", ".names"))
    missing = [p.name for p in files if not p.is_file() or p.stat().st_size == 0]
    pointers = [p.name for p in files if p.name not in missing and _is_lfs_pointer(p)]
    if missing or pointers:
        return [fail("models", f"{', '.join(missing + pointers)} in {shipped.MODELS} "
                               f"{'missing' if missing else 'are Git LFS pointers'}: reinstall uav-tui "
                               "(pip install -e .), after git lfs pull in a clone")]
    return [ok("models", f"{len(files)} files in {shipped.MODELS} (nanotrack, yolo-fastest)")]


def _is_lfs_pointer(path: Path) -> bool:
    with path.open("rb") as file:
        return file.read(len(LFS_POINTER)) == LFS_POINTER


def cpu(governor: Path = GOVERNOR) -> list[Finding]:
    """The CPU frequency governor, and on a Pi whether it is throttled or short of power."""
    found = []
    try:
        name = governor.read_text(encoding="utf-8").strip()
    except OSError:
        name = ""
    if name == "powersave":
        found.append(warn("cpu", "governor powersave: the processor runs slowly; echo performance | sudo tee "
                                 "/sys/devices/system/cpu/cpu*/cpufreq/scaling_governor"))
    elif name:
        found.append(ok("cpu", f"governor {name}"))
    done, output = run_tool("vcgencmd", "get_throttled")
    if done and "=" in output:
        found.append(_throttled(int(output.split("=", 1)[1].strip(), 16)))
    return found


def _throttled(bits: int) -> Finding:
    if bits & UNDER_VOLTAGE_NOW:
        return fail("power", f"under-voltage now (get_throttled 0x{bits:x}): the Pi can reset in flight; use a "
                             "supply or BEC that gives 5.1 V at 3 A (5 A on a Pi 5)")
    if bits & THROTTLE_NOW:
        return warn("power", f"throttled now (get_throttled 0x{bits:x}): cool the Pi (heatsink, fan) or check power")
    if bits >> 16:
        return warn("power", f"under-voltage or throttling since boot (get_throttled 0x{bits:x}): check the supply "
                             "and cooling under load")
    return ok("power", "no under-voltage or throttling since boot")


def token(config: Config, weak: str) -> Finding:
    """The web page's token: ``weak`` is the configured one the platform would refuse ("" when none was)."""
    if weak and (problem := token_problem(weak)):
        return fail("web token", f"web_token {problem}")
    if not config.web.web:
        return ok("web token", "web page off")
    if not config.web.web_token:
        return ok("web token", "web_token empty: a random one each start")
    return ok("web token", f"about {token_bits(config.web.web_token):.0f} bits (at least {MIN_TOKEN_BITS} needed)")
