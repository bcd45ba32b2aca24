"""A dead link never keeps uav-tui alive: MAVSDK calls are bounded and abandoned at shutdown.

Reproduces the hang seen in the field: autonomy flying, the autopilot stops answering (here the
simulator is frozen with SIGSTOP: the link is up, nothing answers), ``hold`` is sent, then the
operator stops uav-tui. A thread blocked in ``Action.hold()`` kept the interpreter alive forever.
"""

from __future__ import annotations

import os
import queue
import signal
import threading
from pathlib import Path

import pytest

from controllers.sim.launcher import SimVehicle
from tests.core.flight_helpers import speed, start_steering_flight
from tests.core.test_autopilot_failsafe import wait_for
from uav_tui.headless import EXIT_ABANDONED

SCRIPT = "arm\ntakeoff 3\nwait 6\nf 1\nautonomy on\nwait 4\nhold\nwait 120\n"


def read_lines(stream, lines: queue.Queue[str]) -> None:
    for line in stream:
        lines.put(line)
    lines.put("")


def wait_line(lines: queue.Queue[str], text: str, seen: list[str], timeout: float = 60) -> None:
    while True:
        line = lines.get(timeout=timeout)
        seen.append(line)
        if not line:
            raise AssertionError(f"uav-tui exited before printing {text!r}:\n{''.join(seen)}")
        if text in line:
            return


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_frozen_autopilot_during_hold_does_not_keep_uav_tui_alive(tmp_path: Path, sim_vehicle: SimVehicle,
                                                                   signum: int) -> None:
    process = start_steering_flight(tmp_path, sim_vehicle.connection_string, SCRIPT)
    lines: queue.Queue[str] = queue.Queue()
    reader = threading.Thread(target=read_lines, args=(process.stdout, lines), daemon=True)
    reader.start()
    seen: list[str] = []
    truth = sim_vehicle.truth()
    frozen = False
    try:
        wait_for(lambda: (s := truth.latest()) is not None and s["mode"] == "OFFBOARD" and speed(s) > 0.3, 40,
                 "uav-tui to fly a vector")
        os.kill(sim_vehicle.pid, signal.SIGSTOP)
        frozen = True
        wait_line(lines, "command: hold", seen)
        process.send_signal(signum)
        process.wait(timeout=30)  # it used to hang here forever, whatever signal it was sent
        while (line := lines.get(timeout=5)) != "":
            seen.append(line)
    finally:
        if frozen:
            os.kill(sim_vehicle.pid, signal.SIGCONT)
        process.kill()
        process.wait()
        reader.join(5)
        process.stdout.close()
        truth.close()
    out = "".join(seen)
    assert "hold before exit failed" in out, out
    assert "stopped: " in out, (process.returncode, out[-600:])
    # Non-zero exactly when a MAVSDK call was still blocked at the end (then it says which).
    abandoned = "flight controller calls still blocked, abandoned" in out
    assert process.returncode == (EXIT_ABANDONED if abandoned else 0), out
