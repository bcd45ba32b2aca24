"""The simulator's MAVLink socket where the kernel lacks receive timestamps (emulated arm64: ENOPROTOOPT)."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from controllers.sim import link
from controllers.sim.launcher import free_udp_port

ROOT = Path(__file__).resolve().parents[2]
UNKNOWN_SOCKET_OPTION = 9999
"""The kernel answers ENOPROTOOPT for it, as an emulator does for SO_TIMESTAMPNS."""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="receive timestamps are requested on Linux only")
def test_link_falls_back_to_the_time_of_reading(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(link, "_SO_TIMESTAMPNS", UNKNOWN_SOCKET_OPTION)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as ground:
        ground.bind(("127.0.0.1", 0))
        mav = link.MavlinkLink(ground.getsockname()[1])
        try:
            heartbeat = mav.encoder.heartbeat_encode(2, 12, 0, 0, 0)
            ground.sendto(heartbeat.pack(link.mavlink.MAVLink(None, 255, 190)), mav._sock.getsockname())
            before = time.monotonic_ns()
            messages, arrival_ns = mav.receive()
        finally:
            mav.close()
    assert [m.get_type() for m in messages] == ["HEARTBEAT"]
    assert before <= arrival_ns <= time.monotonic_ns()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="receive timestamps are requested on Linux only")
def test_simulator_starts_without_receive_timestamps() -> None:
    code = (f"import sys, controllers.sim.link as link; link._SO_TIMESTAMPNS = {UNKNOWN_SOCKET_OPTION}; "
            "from controllers.sim.__main__ import main; sys.exit(main(sys.argv[1:]))")
    process = subprocess.Popen([sys.executable, "-c", code, "--mavlink-port", str(free_udp_port()),
                                "--truth-port", "0", "--parent-pid", str(os.getpid())], cwd=ROOT,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert process.stdout is not None
        ready = process.stdout.readline()
    finally:
        process.terminate()
        _, stderr = process.communicate(timeout=10)
    assert ready, stderr
    assert "truth port" not in stderr


def test_a_busy_truth_port_is_named_as_the_cause() -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as busy:
        busy.bind(("127.0.0.1", 0))
        port = busy.getsockname()[1]
        result = subprocess.run([sys.executable, "-m", "controllers.sim", "--mavlink-port", str(free_udp_port()),
                                 "--truth-port", str(port)], cwd=ROOT, capture_output=True, text=True, timeout=30)
    assert result.returncode == 2
    assert f"uav-tui sim: error: cannot start the simulated vehicle: [Errno 98] cannot open the truth port {port}" \
           in result.stderr
