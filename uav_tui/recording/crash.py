"""A crash of the platform's own process leaves every thread's Python stack in the run folder.

A segfault or an abort in native code (the researcher's with ``isolation = "thread"``, or FFmpeg's,
MAVSDK's, PyAV's) ends the process at once: no event, no hold, rows up to the last flush, and on the
dashboard a frozen screen. While a run is recorded, :mod:`faulthandler` writes the stacks to
``crash.txt``; a run that ends normally removes the empty file. ``uav-tui report`` and ``uav-tui
runs`` say where such a run died (:func:`crash_summary`).
"""

from __future__ import annotations

import contextlib
import faulthandler
import itertools
import re
import sys
from pathlib import Path

from uav_tui.output.text import safe, shorten

CRASH_FILE = "crash.txt"
SUMMARY_CHARS = 300
"""The longest summary (a path can be long)."""
_FRAME = re.compile(r'^\s+File "(?P<file>[^"]*)", line (?P<line>\d+) in (?P<function>.*)$')


class CrashRecord:
    """Points :mod:`faulthandler` at ``run_dir/crash.txt`` until :meth:`close`."""

    def __init__(self, run_dir: Path) -> None:
        self.path = run_dir / CRASH_FILE
        self._was_enabled = faulthandler.is_enabled()
        self._file = self.path.open("w", encoding="utf-8")
        faulthandler.enable(self._file, all_threads=True)

    def close(self) -> None:
        """The run ended: nothing crashed. Remove the file; give faulthandler back to stderr if it was on."""
        faulthandler.disable()
        self._file.close()
        self.path.unlink(missing_ok=True)
        if self._was_enabled and sys.__stderr__ is not None:
            with contextlib.suppress(AttributeError, OSError, ValueError, RuntimeError):  # no stderr to point at
                faulthandler.enable(sys.__stderr__, all_threads=True)


def crash_summary(run_dir: Path) -> str | None:
    """``Fatal Python error: Segmentation fault in string_at (…:519), called from customize_processing
    (mine.py:6)`` for a run whose process crashed, else None. Escaped and bounded."""
    try:
        with (run_dir / CRASH_FILE).open(encoding="utf-8", errors="replace") as file:
            lines = file.read(64 * 1024).splitlines()
    except OSError:
        return None
    if not lines:
        return None
    current = next((i for i, line in enumerate(lines) if line.startswith("Current thread")), len(lines))
    frames = [m for m in itertools.takewhile(bool, map(_FRAME.match, lines[current + 1:])) if m]
    where = [f"{m['function']} ({m['file']}:{m['line']})" for m in frames[:2]]
    text = lines[0].strip()
    if where:
        text += f" in {where[0]}"
    if len(where) > 1:
        text += f", called from {where[1]}"
    return safe(shorten(text, SUMMARY_CHARS))
