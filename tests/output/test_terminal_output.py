"""Output to a terminal that stops taking it (the dashboard's, ``--no-ui``'s): a real pipe whose reader pauses is the
terminal."""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections.abc import Iterator
from typing import TextIO

import pytest

from uav_tui.output.terminal_output import TerminalOutput

KEPT = 64  # the dashboard's terminal modes


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
    dropped: list[int] = []
    drained = threading.Event()
    output = TerminalOutput(file, lambda n: (dropped.append(n), drained.set()), pytest.fail, max_backlog=200_000,
                            kept_write_chars=KEPT)
    update = "x" * 50_000  # a screen update
    started = time.monotonic()
    for i in range(40):  # 2 MB, far more than the pipe and the backlog hold
        assert output.write(update) == len(update)  # as a text file's write does, kept or dropped
        output.write(f"\x1b[?{i}h")  # a terminal mode: short, never dropped
    output.write("END")
    assert time.monotonic() - started < 1.0  # nothing waited for the reader (a blocked write waits forever)
    assert not drained.is_set()
    text = read_all(read_fd, b"END").decode()
    assert drained.wait(5)  # everything kept was written, after updates had been dropped: repaint
    assert text.count(update) < 40  # updates were dropped, whole, and counted
    assert dropped == [40 - text.count(update)]
    assert text.replace(update, "") == "".join(f"\x1b[?{i}h" for i in range(40)) + "END"
    output.close(1.0)


def test_without_a_stall_nothing_is_dropped_and_close_writes_the_rest(terminal) -> None:
    read_fd, file = terminal
    drained = threading.Event()
    output = TerminalOutput(file, lambda n: drained.set(), pytest.fail, max_backlog=200_000, kept_write_chars=KEPT)
    updates = [f"update {i} " * 20 for i in range(100)]
    assert all(len(u) > KEPT for u in updates)
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


def test_a_terminal_that_is_gone_is_reported_and_writes_go_on_without_raising() -> None:
    read_fd, write_fd = os.pipe()
    os.close(read_fd)  # the reader is gone: writing fails with EPIPE
    file = os.fdopen(write_fd, "w")
    errors: list[OSError] = []
    failed = threading.Event()
    output = TerminalOutput(file, pytest.fail, lambda exc: (errors.append(exc), failed.set()))
    output.write("lost line\n")
    assert failed.wait(5)
    output.write("another\n")
    output.close(5.0)
    with contextlib.suppress(BrokenPipeError):  # what it could not write is still in the file's buffer
        file.close()
    assert errors and all(isinstance(exc, BrokenPipeError) for exc in errors)
