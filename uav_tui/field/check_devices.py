"""``doctor``'s checks of the devices: the cameras (which is which) and the flight controller's serial port."""

from __future__ import annotations

import grp
import os
import stat
import threading
import time
from pathlib import Path

from controllers.connection import Connection, check_serial_device
from controllers.errors import ConnectError
from uav_tui.config import Config
from uav_tui.field.finding import Finding, fail, ok
from uav_tui.field.tools import run_tool

V4L_DIR = Path("/sys/class/video4linux")
CMDLINE_FILES = (Path("/boot/firmware/cmdline.txt"), Path("/boot/cmdline.txt"))
"""The kernel command line on Raspberry Pi OS bookworm, and before it."""
PI_UARTS = ("/dev/serial0", "/dev/ttyAMA0", "/dev/ttyS0", "/dev/serial1")
CONSOLES = ("console=serial0", "console=ttyAMA0", "console=ttyS0", "console=serial1")
PROBE_TIMEOUT_S = 3.0
"""Longest an OpenCV probe of one camera may take (a wedged UVC camera can block ``open`` for good)."""
PROBE_BUDGET_S = 6.0
"""Longest all probes together may take (a Pi has a dozen codec and ISP nodes besides its cameras)."""


def cameras(config: Config, v4l_dir: Path = V4L_DIR) -> list[Finding]:
    """One line per camera device (its name and formats), and whether the configured ``usb:`` camera is there."""
    devices = sorted(v4l_dir.glob("video*"), key=lambda p: int(p.name.removeprefix("video") or 0)) \
        if v4l_dir.is_dir() else []
    deadline = time.monotonic() + PROBE_BUDGET_S
    found = [ok("camera", f"/dev/{d.name}: {_read(d / 'name') or 'unnamed'}; {_formats(f'/dev/{d.name}', deadline)}")
             for d in devices]
    scheme, _, target = config.source.partition(":")
    if scheme != "usb":
        return found or [ok("camera", f"no camera devices; source {config.source} needs none")]
    device = f"/dev/video{target or 0}" if (target or "0").isdigit() else target
    if not Path(device).exists():
        present = ", ".join(f"/dev/{d.name}" for d in devices) or "none"
        found.append(fail("camera", f"source {config.source}: no {device} (camera devices: {present}); plug the "
                                    "camera in, or set source to one listed above (usb:N is /dev/videoN)"))
    return found


def _read(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8", errors="replace").strip()
    except OSError:
        return ""


def _formats(device: str, deadline: float) -> str:
    """What ``v4l2-ctl --list-formats`` says (the FourCCs), else an OpenCV probe's FourCC and size, until
    ``deadline``."""
    if (left := min(PROBE_TIMEOUT_S, deadline - time.monotonic())) <= 0:
        return "formats not probed (time is up; apt install v4l-utils to list them)"
    done, output = run_tool("v4l2-ctl", "-d", device, "--list-formats", timeout_s=left)
    if done:
        fourccs = [line.split("'")[1] for line in output.splitlines() if line.count("'") >= 2]
        return "formats " + (", ".join(fourccs) or "none (a metadata node, not a camera)")
    found: list[str] = []
    probe = threading.Thread(target=_probe, args=(device, found), name=f"doctor-probe:{device}", daemon=True)
    probe.start()
    probe.join(left)  # a probe still blocked is left behind: the process ends soon
    if not found:
        return "formats unknown (OpenCV could not open it in time; apt install v4l-utils to list them)"
    return found[0] + " (OpenCV; apt install v4l-utils to list all formats)"


def _probe(device: str, found: list[str]) -> None:
    import cv2

    capture = cv2.VideoCapture(device, cv2.CAP_V4L2)
    try:
        if capture.isOpened():
            code = int(capture.get(cv2.CAP_PROP_FOURCC))
            fourcc = "".join(chr(code >> (8 * i) & 0xFF) for i in range(4)).strip("\0") or "?"
            found.append(f"format {fourcc} {int(capture.get(cv2.CAP_PROP_FRAME_WIDTH))}x"
                         f"{int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT))}")
    finally:
        capture.release()


def serial_port(connection: Connection, cmdline_files: tuple[Path, ...] = CMDLINE_FILES) -> list[Finding]:
    """The serial device: there, ours to open (its group), free; and not also the Pi's login console."""
    device = connection.device or ""
    found: list[Finding] = []
    try:
        check_serial_device(device)
    except ConnectError as exc:
        found.append(fail("serial", f"{exc}{_ownership(device)}"))
    else:
        found.append(ok("serial", f"{device} opens{_ownership(device)}"))
    cmdline = next((_read(path) for path in cmdline_files if path.is_file()), "")
    console = next((word for word in cmdline.split() if word.startswith(CONSOLES)), "")
    if console and os.path.realpath(device) in {os.path.realpath(uart) for uart in PI_UARTS}:
        found.append(fail("serial", f"the Pi's serial console is on ({console} in cmdline.txt) on the UART the "
                                    "autopilot uses: sudo raspi-config (Interface options, Serial port: login shell "
                                    "no, hardware yes), or delete that word from cmdline.txt; reboot"))
    return found


def _ownership(device: str) -> str:
    """`` (group dialout, crw-rw----)`` for an existing device, with ``you are not in it`` when so; else ""."""
    try:
        info = os.stat(device)
    except OSError:
        return ""
    try:
        group = grp.getgrgid(info.st_gid).gr_name
    except KeyError:
        group = str(info.st_gid)
    member = info.st_gid in os.getgroups() or os.getgid() == info.st_gid
    return f" (group {group}, {stat.filemode(info.st_mode)}{'' if member else '; you are not in that group'})"
