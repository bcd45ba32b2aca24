"""Starting and stopping the simulator process, and its ground-truth channel."""

from __future__ import annotations

import os
import signal
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path

import pytest

from controllers.sim import launcher
from controllers.sim.__main__ import build_parser, config_from_args
from controllers.sim.launcher import REPO_ROOT, SimVehicle, free_ports
from uav_tui.errors import ControllerError


def test_start_stop_is_idempotent_and_exits_cleanly() -> None:
    sim = SimVehicle()
    assert sim.stop() is None  # never started
    sim.start()
    pid = sim.pid
    assert pid is not None and sim.running
    assert sim.connection_string == f"udpin://127.0.0.1:{sim.mavlink_port}"
    assert sim.mavlink_port != sim.truth_port
    assert sim.stop() == 0  # SIGTERM is a clean exit
    assert sim.stop() is None
    assert not sim.running
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)


@pytest.mark.parametrize("kind", [socket.SOCK_DGRAM, socket.SOCK_STREAM], ids=["udp", "tcp"])
def test_free_ports_are_distinct_bindable_and_below_the_ephemeral_range(kind: socket.SocketKind) -> None:
    ephemeral_start = int(Path("/proc/sys/net/ipv4/ip_local_port_range").read_text().split()[0])
    ports = free_ports(5, kind)
    assert len(set(ports)) == 5
    assert all(launcher.LOWEST_PORT <= port < ephemeral_start for port in ports)
    for port in ports:
        with socket.socket(socket.AF_INET, kind) as sock:
            sock.bind(("127.0.0.1", port))


def test_free_ports_skip_ports_in_use(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    window = range(launcher.LOWEST_PORT, launcher.LOWEST_PORT + 20)
    port_range = tmp_path / "ip_local_port_range"
    port_range.write_text(f"{window.stop}\t60999\n")
    monkeypatch.setattr(launcher, "EPHEMERAL_PORTS", port_range)
    held: list[socket.socket] = []
    try:
        for port in window:  # take all but the last two that are free
            sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            try:
                sock.bind(("127.0.0.1", port))
            except OSError:
                sock.close()
                continue
            held.append(sock)
        left = [s.getsockname()[1] for s in held[-2:]]
        for sock in held[-2:]:
            sock.close()
        assert sorted(free_ports(2)) == left
        with pytest.raises(OSError, match="no 3 free ports from"):
            free_ports(3)
    finally:
        for sock in held:
            sock.close()


def _alive(pid: int) -> bool:
    status = Path(f"/proc/{pid}/status")
    try:
        return "\nState:\tZ" not in status.read_text()
    except FileNotFoundError:
        return False


def test_simulator_exits_when_its_parent_dies_without_stopping_it() -> None:
    script = (
        "from controllers.sim.launcher import SimVehicle; import time\n"
        "print(SimVehicle().start().pid, flush=True)\n"
        "time.sleep(30)\n"
    )
    env = {**os.environ, "PYTHONPATH": str(REPO_ROOT)}
    with subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, env=env, cwd=REPO_ROOT) as parent:
        assert parent.stdout is not None
        pid = int(parent.stdout.readline())
        assert _alive(pid)
        parent.kill()
    deadline = time.monotonic() + 5.0
    while _alive(pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _alive(pid)


def test_simulator_outlives_a_hangup_of_its_parents_job() -> None:
    """Like an autopilot, it is stopped by the platform, not by the hang-up sent to every process of the job."""
    script = (
        "from controllers.sim.launcher import SimVehicle; import signal, time\n"
        "signal.signal(signal.SIGHUP, lambda *_: None)  # the platform handles its hang-up\n"
        "print(SimVehicle().start().pid, flush=True)\n"
        "time.sleep(30)\n"
    )
    env = {**os.environ, "PYTHONPATH": str(REPO_ROOT)}
    with subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, env=env, cwd=REPO_ROOT,
                          start_new_session=True) as parent:
        try:
            assert parent.stdout is not None
            pid = int(parent.stdout.readline())
            os.killpg(parent.pid, signal.SIGHUP)
            time.sleep(0.5)
            assert _alive(pid)
        finally:
            parent.kill()  # the simulator follows its parent (the test above)


def test_start_failure_quotes_the_simulator_output() -> None:
    sim = SimVehicle(extra_args=["--no-such-option"])
    with pytest.raises(ControllerError, match="--no-such-option"):
        sim.start(timeout=5.0)
    assert not sim.running


def test_truth_stream_and_requests(sim_vehicle: SimVehicle) -> None:
    truth = sim_vehicle.truth()
    first = truth.wait_latest()
    assert {
        "t_mono_ns",
        "t_wall_ns",
        "n",
        "e",
        "d",
        "vn",
        "ve",
        "vd",
        "roll",
        "pitch",
        "yaw",
        "armed",
        "mode",
        "in_air",
        "lat",
        "lon",
        "alt",
    } <= first.keys()
    assert (first["lat"], first["lon"], first["alt"]) == pytest.approx((47.397742, 8.545594, 488.0))
    assert first["mode"] == "HOLD" and not first["armed"]
    assert abs(first["t_mono_ns"] - time.monotonic_ns()) < 1e9  # one clock for every process
    assert 0 < first["time_boot_ms"] < 10_000
    time.sleep(0.5)
    assert (truth.latest()["t_mono_ns"] - first["t_mono_ns"]) / 1e9 > 0.4  # still streaming

    moved = truth.request({"cmd": "teleport", "n": 3.0, "e": -4.0, "d": -2.0, "yaw": 45.0})["state"]
    assert (moved["n"], moved["e"], moved["d"], moved["yaw"]) == pytest.approx((3.0, -4.0, -2.0, 45.0))
    assert truth.request({"cmd": "set_wind", "n": 1.5, "e": -0.5})["ok"]
    time.sleep(0.2)
    state = truth.request({"cmd": "state"})["state"]
    assert (state["wind_n"], state["wind_e"]) == (1.5, -0.5)
    assert state["d"] > -2.0  # disarmed in the air: it falls
    setpoints = truth.request({"cmd": "setpoints", "since_mono_ns": 0})
    assert setpoints["records"] == [] and setpoints["more"] is False
    bad = truth.request({"cmd": "fly_to_the_moon"})
    assert not bad["ok"] and "fly_to_the_moon" in bad["error"]


def test_truth_stream_rate_is_about_50_hz(sim_vehicle: SimVehicle) -> None:
    truth = sim_vehicle.truth()
    truth.wait_latest()
    seen: set[int] = set()
    while len(seen) < 20:
        seen.add(truth.wait_latest()["t_mono_ns"])
    stamps = sorted(seen)
    # Spacing on the simulator's own clock: 20 ms steps (a late step on a loaded machine moves few of them).
    assert statistics.median(b - a for a, b in zip(stamps, stamps[1:], strict=False)) / 1e6 < 30


def test_cli_options_reach_the_configuration() -> None:
    args = build_parser().parse_args(
        [
            "--mavlink-port",
            "14999",
            "--home",
            "40.0,-3.5,650",
            "--wind",
            "2,-1",
            "--offboard-loss-timeout",
            "0.5",
            "--failsafe-land-after",
            "3",
            "--noise",
            "--speed-time-constant",
            "0.3",
            "--seed",
            "9",
        ]
    )
    cfg = config_from_args(args)
    assert cfg.mavlink_port == 14999 and cfg.wind == (2.0, -1.0) and cfg.seed == 9
    assert (cfg.home.lat_deg, cfg.home.lon_deg, cfg.home.alt_m) == (40.0, -3.5, 650.0)
    assert cfg.offboard_loss_timeout_s == 0.5 and cfg.failsafe_land_after_s == 3.0
    assert cfg.physics.noise and cfg.physics.speed_time_constant_s == 0.3
    with pytest.raises(SystemExit):
        build_parser().parse_args(["--home", "north pole"])
