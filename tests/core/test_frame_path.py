"""A frame's way from capture to the MAVSDK call passes few enough files for a reader to follow it.

Traced with ``sys.settrace`` on a real flight (the built-in simulator through the real MAVSDK controller, nothing
faked): the project's files on the Python stack where each thread hands the frame on (the capture thread from
``FrameBuffer.put`` to the processor's host, the host's thread to the processor, the loop to the autonomy gate, the
gate's task to MAVSDK's ``send_message``), the gate's task holding that very frame. ``docs/architecture.md`` lists
them ("One frame, capture to MAVSDK"); the trace must find that list.
"""

from __future__ import annotations

import re
import sys
import threading
from pathlib import Path
from types import CodeType, FrameType
from typing import Any

from sources.buffer import FrameBuffer
from tests.core.flight_helpers import flying_core, wait_until
from uav_tui.flight.autonomy import AutonomyGate
from uav_tui.hosting.frame_call import call_frame
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.thread_host import ThreadHost

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("uav_tui", "sources", "processors", "controllers", "uav_values")
"""The project's own code: what a reader has to open (the researcher's processor and MAVSDK are the two ends)."""
MAX_FILES = 10
KEPT = 300
"""Frames whose hops are kept (the oldest are let go)."""


class FramePath:
    """Records, for each frame (by its image), the project's files on the stack at each hand-off."""

    def __init__(self) -> None:
        self.hops: dict[int, tuple[object, dict[str, list[str]]]] = {}
        self._lock = threading.Lock()  # three threads record
        self._handed = {ThreadHost._on_frame.__code__: "capture", call_frame.__code__: "processor",
                        AutonomyGate.consider.__code__: "gate"}

    def trace(self, frame: FrameType, event: str, arg: Any) -> None:
        if event != "call":
            return None
        hop = self._handed.get(frame.f_code)
        if hop is not None:
            image = frame.f_locals["image"] if hop == "processor" else (
                frame.f_locals["frame"].image if hop == "capture" else frame.f_locals["result"].frame.image)
            self._hops(image)[hop] = _files(frame, FrameBuffer.put.__code__ if hop == "capture" else None)
        elif frame.f_code.co_name == "send_message" and "site-packages/mavsdk/" in frame.f_code.co_filename:
            result = _held(frame.f_back)
            if result is not None:
                self._hops(result.frame.image).setdefault("mavsdk", _files(frame.f_back))
        return None

    def _hops(self, image: object) -> dict[str, list[str]]:
        """The hops of the frame whose image this is (kept alive with its record: its id is not reused)."""
        with self._lock:
            kept = self.hops.get(id(image))
            if kept is None:
                kept = self.hops[id(image)] = (image, {})
                if len(self.hops) > KEPT:
                    del self.hops[next(iter(self.hops))]
            return kept[1]

    def flown(self) -> list[dict[str, list[str]]]:
        """The hops of every frame that went all the way, in the order they happened."""
        with self._lock:
            return [hops for _, hops in self.hops.values() if len(hops) == 4]


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


def documented() -> list[str]:
    """The files ``docs/architecture.md`` lists between its ``frame-path`` marks, in order."""
    text = (ROOT / "docs" / "architecture.md").read_text()
    block = text[text.index("<!-- frame-path"):text.index("<!-- /frame-path -->")]
    return re.findall(r"^\d+\. `([^`]+)`", block, re.MULTILINE)


def _held(frame: FrameType | None) -> ProcessedFrame | None:
    """The processed frame a function on this stack holds (the gate's sender has the one it is flying)."""
    while frame is not None:
        for value in frame.f_locals.values():
            if isinstance(value, ProcessedFrame):
                return value
        frame = frame.f_back
    return None


async def test_a_frame_reaches_the_mavsdk_call_through_at_most_ten_files(tmp_path: Path) -> None:
    path = FramePath()
    threading.settrace(path.trace)  # the capture and processor threads, started by the core below
    sys.settrace(path.trace)
    try:
        async with flying_core(tmp_path, isolation="thread") as core:
            await core.execute("f 1")
            await core.execute("autonomy on")
            await wait_until(lambda: path.flown(), 20, "a frame's vector sent to the vehicle")
    finally:
        sys.settrace(None)
        threading.settrace(None)  # type: ignore[arg-type]
    hops = path.flown()[0]
    files = list(dict.fromkeys(file for hop in ("capture", "processor", "gate", "mavsdk") for file in hops[hop]))
    assert len(files) <= MAX_FILES, files
    assert files == documented()
