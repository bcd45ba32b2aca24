"""Running the system's tools (systemctl, journalctl, v4l2-ctl, timedatectl, vcgencmd): bounded, never a terminal."""

from __future__ import annotations

import shutil
import subprocess

TOOL_TIMEOUT_S = 5.0
"""Longest a tool may take by default."""


def run_tool(*command: str, timeout_s: float = TOOL_TIMEOUT_S) -> tuple[bool, str]:
    """Run ``command``; (it exited 0, its output), or (False, why it could not run)."""
    if shutil.which(command[0]) is None:
        return False, f"{command[0]} not found"
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout_s, stdin=subprocess.DEVNULL,
                              check=False)
    except subprocess.TimeoutExpired:
        return False, f"{command[0]} did not answer within {timeout_s:g} s"
    except OSError as exc:
        return False, f"cannot run {command[0]}: {exc.strerror or exc}"
    return done.returncode == 0, done.stdout + done.stderr
