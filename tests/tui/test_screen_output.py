"""The dashboard's output to a terminal that stops taking it: a real pipe whose reader pauses is the terminal."""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Iterator
from typing import TextIO

import pytest

from uav_tui.tui._terminal import KEPT_WRITE_CHARS, ScreenOutput


@pytest.fixture
def terminal() -> Iterator[tuple[int, TextIO]]:
    """(read end, write end as a text file) of a pipe: writing blocks once its 64 KiB buffer is full."""
    read_fd, write_fd = os.pipe()
    with os.fdopen(write_fd, "w") as file:
        yield read_fd, file
    os.close(read_fd)


def read_all(read_fd: int, until: bytes) -> bytes:
    data = b""
    while not data.endswith(until):
        data += os.read(read_fd, 1 << 16)
    return data


def test_writes_never_wait_for_a_stalled_terminal_and_the_screen_is_repainted_once_it_drains(terminal) -> None:
    read_fd, file = terminal
    drained = threading.Event()
    output = ScreenOutput(file, drained.set, max_backlog=200_000)
    update = "x" * 50_000  # a screen update
    started = time.monotonic()
    for i in range(40):  # 2 MB, far more than the pipe and the backlog hold
        output.write(update)
        output.write(f"\x1b[?{i}h")  # a terminal mode: short, never dropped
    output.write("END")
    assert time.monotonic() - started < 1.0  # nothing waited for the reader (a blocked write waits forever)
    assert not drained.is_set()
    text = read_all(read_fd, b"END").decode()
    assert drained.wait(5)  # everything kept was written, after updates had been dropped: repaint
    assert text.count(update) < 40  # updates were dropped, whole
    assert text.replace(update, "") == "".join(f"\x1b[?{i}h" for i in range(40)) + "END"
    output.close(1.0)


def test_without_a_stall_nothing_is_dropped_and_close_writes_the_rest(terminal) -> None:
    read_fd, file = terminal
    drained = threading.Event()
    output = ScreenOutput(file, drained.set, max_backlog=200_000)
    updates = [f"update {i} " * 20 for i in range(100)]
    assert all(len(u) > KEPT_WRITE_CHARS for u in updates)
    reader = threading.Thread(target=lambda: received.append(read_all(read_fd, b"END")))
    received: list[bytes] = []
    reader.start()
    for update in updates:
        output.write(update)
    output.write("END")
    output.close(5.0)
    reader.join(5)
    assert received == ["".join(updates).encode() + b"END"]
    assert not drained.is_set()  # nothing was dropped: no repaint needed
