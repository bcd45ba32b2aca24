"""A real ``uav-tui --no-ui --web`` under a 200-descriptor limit, recording, and 250 idle connections from loopback
addresses that are not the operator's (127.0.0.2-51): the page takes what its budget allows and closes the rest at
once, aiohttp times the idle ones out, the operator still gets the page, nothing floods the output or costs the
recorder its files, and a processor that exits meanwhile is restarted (issue 47, 4)."""

from __future__ import annotations

import csv
import os
import resource
import socket
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.web.conftest import TOKEN, free_port, interrupt

ROOT = Path(__file__).resolve().parents[2]
DESCRIPTORS = 200
STRANGERS = 250

DIES_ON_MARKER = '''
import os
from pathlib import Path


class DiesOnMarker:
    """Exits when the file ``die`` appears (once: it deletes it; the restarted one goes on)."""

    def photo_processing(self, frame):
        marker = Path("die")
        if marker.exists():
            marker.unlink()
            os._exit(4)
'''


def _limit_descriptors() -> None:
    resource.setrlimit(resource.RLIMIT_NOFILE, (DESCRIPTORS, DESCRIPTORS))


def _wait_for(path: Path, text: str, timeout_s: float) -> str:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        output = path.read_text(errors="replace")
        if text in output:
            return output
        time.sleep(0.2)
    raise AssertionError(f"{text!r} not in the output within {timeout_s:g} s:\n{path.read_text()[-3000:]}")


@pytest.fixture
def platform(tmp_path: Path) -> Iterator[tuple[int, Path, subprocess.Popen[bytes]]]:
    (tmp_path / "dies.py").write_text(DIES_ON_MARKER)
    port = free_port()
    output = tmp_path / "output.txt"
    with open(output, "w") as sink:
        process = subprocess.Popen(
            [sys.executable, "-m", "uav_tui", "--no-ui", "--fc", "none", "--source", "synthetic:", "--processor",
             "dies.py:DiesOnMarker", "--web", "--web-host", "127.0.0.1", "--web-port", str(port), "--web-token",
             TOKEN, "--runs-dir", "runs", "--duration", "90"],
            cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)}, stdout=sink, stderr=subprocess.STDOUT,
            preexec_fn=_limit_descriptors)
    try:
        _wait_for(output, "web page: http://", 60)
        yield port, output, process
    finally:
        interrupt(process, 30)


def _still_open(sock: socket.socket) -> bool:
    """Whether the server has not closed ``sock`` (nothing to read yet, no end, no reset)."""
    sock.setblocking(False)
    try:
        return sock.recv(1) != b""
    except BlockingIOError:
        return True
    except OSError:
        return False


def test_idle_strangers_cannot_take_the_descriptors(platform: tuple[int, Path, subprocess.Popen[bytes]]) -> None:
    port, output, process = platform
    page_url = f"http://127.0.0.1:{port}/?token={TOKEN}"
    with urllib.request.urlopen(page_url, timeout=10) as page:  # the operator has the page open
        assert page.status == 200
    strangers = []
    try:
        for n in range(STRANGERS):
            sock = socket.socket()
            sock.bind((f"127.0.0.{2 + n % 50}", 0))
            sock.connect(("127.0.0.1", port))
            strangers.append(sock)
        (output.parent / "die").touch()  # the processor exits while they are held
        with urllib.request.urlopen(page_url, timeout=10) as page:
            assert page.status == 200  # the operator's address still gets the page
        _wait_for(output, "processor restarted", 30)
        time.sleep(1.0)
        held = [sock for sock in strangers if _still_open(sock)]
        assert len(held) <= 64  # at most the page's budget; the rest were closed at once
        deadline = time.monotonic() + 15
        while held and time.monotonic() < deadline:  # idle ones are timed out (5 s)
            time.sleep(0.5)
            held = [sock for sock in held if _still_open(sock)]
        assert held == []
    finally:
        for sock in strangers:
            sock.close()
    assert process.poll() is None
    interrupt(process, 30)
    printed = output.read_text(errors="replace")
    assert "Traceback" not in printed and "out of system resource" not in printed
    assert "Too many open files" not in printed and len(printed.splitlines()) < 100, printed[-3000:]
    assert "closing new connections from 127.0.0." in printed  # said, once
    (run,) = (output.parent / "runs").iterdir()
    with open(run / "events.csv", newline="") as events:
        messages = [row["message"] for row in csv.DictReader(events)]
    assert not any("open files" in m for m in messages)
    assert sum(m.startswith("closing new connections") for m in messages) == 1
    assert any(m.startswith("processor restarted") for m in messages)
