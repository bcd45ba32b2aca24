"""A frame's way from capture to the MAVSDK call passes few enough files for a reader to follow it.

Traced with ``sys.settrace`` on a real flight (the built-in simulator through the real MAVSDK controller, nothing
faked): the project's files on the Python stack where each thread hands the frame on, the gate's task to MAVSDK's
``send_message`` holding that very frame. With ``isolation = "thread"``: the capture thread from ``FrameBuffer.put``
to the processor's host, the host's thread to the processor, the loop to the autonomy gate, the gate's task to
MAVSDK. With ``"process"`` the platform's process is traced (the processor's is another interpreter): the capture
thread from ``FrameBuffer.put`` to the feeder, the feeder's offer in the child's mailbox, the loop from the child's
result to the autonomy gate, the gate's task to MAVSDK. ``docs/architecture.md`` lists them for each ("One frame,
capture to MAVSDK"); the trace must find those lists.
"""

from __future__ import annotations

import re
import sys
import threading
from collections.abc import Callable
from pathlib import Path
from types import CodeType, FrameType
from typing import Any

import pytest

from sources.buffer import FrameBuffer
from tests.core.flight_helpers import flying_core, wait_until
from uav_tui.flight.autonomy import AutonomyGate
from uav_tui.hosting.frame_call import call_frame
from uav_tui.hosting.frame_feeder import FrameFeeder
from uav_tui.hosting.frame_mailbox import FrameMailbox
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.thread_host import ThreadHost

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("uav_tui", "sources", "processors", "controllers", "uav_values")
"""The project's own code: what a reader has to open (the researcher's processor and MAVSDK are the two ends)."""
MAX_FILES = 10
KEPT = 300
"""Frames whose hops are kept (the oldest are let go)."""

Seq = Callable[[dict[str, Any]], int]
"""Which frame a hand-off's function holds, from its arguments: the frame's ``seq``."""

HANDED: dict[str, dict[CodeType, tuple[str, Seq]]] = {
    "thread": {ThreadHost._on_frame.__code__: ("capture", lambda args: args["frame"].seq),
               call_frame.__code__: ("processor", lambda args: args["frame_seq"]),
               AutonomyGate.consider.__code__: ("gate", lambda args: args["result"].frame.seq)},
    "process": {FrameFeeder._on_frame.__code__: ("capture", lambda args: args["frame"].seq),
                FrameMailbox.offer.__code__: ("offer", lambda args: args["offer"].seq),
                AutonomyGate.consider.__code__: ("gate", lambda args: args["result"].frame.seq)},
}
"""Where each thread of the platform's process hands a frame on, by isolation: the function called, the hop's name
and the frame it holds."""


class FramePath:
    """Records, for each frame (by its ``seq``), the project's files on the stack at each hand-off.

    Args:
        isolation: where the processor runs (:data:`HANDED` has its hand-offs).
    """

    def __init__(self, isolation: str) -> None:
        self.hops: dict[int, dict[str, list[str]]] = {}
        self._lock = threading.Lock()  # three threads record
        self._handed = HANDED[isolation]
        self.names = [name for name, _ in self._handed.values()] + ["mavsdk"]

    def trace(self, frame: FrameType, event: str, arg: Any) -> None:
        if event != "call":
            return None
        handed = self._handed.get(frame.f_code)
        if handed is not None:
            name, seq = handed
            self._hops(seq(frame.f_locals))[name] = _files(frame, FrameBuffer.put.__code__)
        elif frame.f_code.co_name == "send_message" and "site-packages/mavsdk/" in frame.f_code.co_filename:
            result = _held(frame.f_back)
            if result is not None:
                self._hops(result.frame.seq).setdefault("mavsdk", _files(frame.f_back))
        return None

    def _hops(self, seq: int) -> dict[str, list[str]]:
        """The hops of frame ``seq``."""
        with self._lock:
            kept = self.hops.get(seq)
            if kept is None:
                kept = self.hops[seq] = {}
                if len(self.hops) > KEPT:
                    del self.hops[next(iter(self.hops))]
            return kept

    def flown(self) -> list[list[str]]:
        """The files of every frame that went all the way, in the order they happened: each hop's, each file once."""
        with self._lock:
            return [list(dict.fromkeys(file for name in self.names for file in hops[name]))
                    for hops in self.hops.values() if len(hops) == len(self.names)]


def _files(frame: FrameType | None, since: CodeType | None = None) -> list[str]:
    """The project's files on the stack from its bottom (or from the call of ``since``) up to ``frame``, each once, in
    the order they were entered."""
    stack: list[str] = []
    while frame is not None:
        path = Path(frame.f_code.co_filename)
        if path.is_relative_to(ROOT) and path.relative_to(ROOT).parts[0] in PACKAGES:
            stack.append(path.relative_to(ROOT).as_posix())
        if frame.f_code is since:
            break
        frame = frame.f_back
    return list(dict.fromkeys(reversed(stack)))


def documented(isolation: str) -> list[str]:
    """The files ``docs/architecture.md`` lists between its ``frame-path`` marks of ``isolation``, in order."""
    text = (ROOT / "docs" / "architecture.md").read_text()
    start = text.index(f"<!-- frame-path {isolation}:")
    block = text[start:text.index("<!-- /frame-path -->", start)]
    return re.findall(r"^\d+\. `([^`]+)`", block, re.MULTILINE)


def _held(frame: FrameType | None) -> ProcessedFrame | None:
    """The processed frame a function on this stack holds (the gate's sender has the one it is flying)."""
    while frame is not None:
        for value in frame.f_locals.values():
            if isinstance(value, ProcessedFrame):
                return value
        frame = frame.f_back
    return None


@pytest.mark.parametrize("isolation", ["thread", "process"])
async def test_a_frame_reaches_the_mavsdk_call_through_the_files_documented(tmp_path: Path, isolation: str) -> None:
    path = FramePath(isolation)
    threading.settrace(path.trace)  # the capture, feeder and processor threads, started by the core below
    sys.settrace(path.trace)
    try:
        async with flying_core(tmp_path, isolation=isolation) as core:
            await core.execute("f 1")
            await core.execute("autonomy on")
            await wait_until(lambda: path.flown(), 20, "a frame's vector sent to the vehicle")
    finally:
        sys.settrace(None)
        threading.settrace(None)  # type: ignore[arg-type]
    files = path.flown()[0]
    assert files == documented(isolation), files
    if isolation == "thread":
        assert len(files) <= MAX_FILES, files
    else:  # from the processor's result on: the platform's files after the child
        assert len(files[files.index("uav_tui/hosting/child_link.py"):]) <= MAX_FILES, files
