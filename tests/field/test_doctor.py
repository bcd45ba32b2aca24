"""``uav-tui doctor`` on this machine and with each field mistake staged narrowly: it names it, says what to do, and
its exit status says whether the setup is flyable (0), blocked (1) or the command was wrong (2)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from controllers.sim.launcher import SimVehicle, free_udp_port
from uav_tui.cli import main as uav_main

ROOT = Path(__file__).resolve().parents[2]
STRONG_TOKEN = "k3uLzq0J0c7WlGx8y0XyqkSOw2n1Qp5M"


def _doctor(tmp_path: Path, capsys: pytest.CaptureFixture[str], toml: str, *flags: str) -> tuple[int, dict[str, str]]:
    """Run ``uav-tui doctor`` on a config of ``toml`` (runs recorded under tmp_path); (exit status, subject -> its
    lines)."""
    (tmp_path / "uav.toml").write_text(f'{toml}\n[recording]\nruns_dir = "{tmp_path / "runs"}"\n', encoding="utf-8")
    code = uav_main(["doctor", "--config", str(tmp_path / "uav.toml"), "--heartbeat-timeout", "1", *flags])
    return code, _by_subject(capsys.readouterr().out)


def _by_subject(out: str) -> dict[str, str]:
    lines: dict[str, str] = {}
    for line in out.splitlines()[1:]:
        level, _, rest = line.partition(" ")
        subject, _, text = rest.strip().partition(": ")
        lines[subject] = (lines.get(subject, "") + f"{level} {text}\n")
    return lines


def test_on_this_machine_a_sim_setup_is_flyable(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, lines = _doctor(tmp_path, capsys, f'[web]\nweb = true\nweb_token = "{STRONG_TOKEN}"\n', "--fc", "sim",
                          "--source", "sim:")
    assert code == 0, lines
    assert {"camera", "fc", "clock", "disk", "models", "web token"} <= set(lines)
    assert lines["models"].startswith("OK") and lines["web token"].startswith("OK about")


def test_each_staged_problem_is_named_with_what_to_do(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A missing camera, nothing behind the UDP port, a disk under min_free_mb, a weak token: four FAILs, exit 1."""
    port = free_udp_port()
    code, lines = _doctor(tmp_path, capsys, f'source = "usb:7"\nfc = "udpin://127.0.0.1:{port}"\n'
                          '[web]\nweb_token = "aaaaaaaaaaaaaaaa"\n', "--min-free-mb", "10000000")
    assert code == 1, lines
    assert lines["camera"].startswith("FAIL") and "no /dev/video7" in lines["camera"] and "plug" in lines["camera"]
    assert lines["heartbeat"].startswith("FAIL no heartbeat") and f"{port}" in lines["heartbeat"]
    assert lines["disk"].startswith("FAIL") and "min_free_mb" in lines["disk"] and "delete old runs" in lines["disk"]
    assert lines["web token"].startswith("FAIL") and "secrets.token_urlsafe" in lines["web token"]


def test_a_serial_port_missing_or_without_permission(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, lines = _doctor(tmp_path, capsys, f'fc = "serial://{tmp_path}/ttyNOPE0:57600"\n')
    assert code == 1 and lines["serial"].startswith("FAIL no serial device") and "heartbeat" not in lines
    port = tmp_path / "ttyFAKE0"  # a file standing for a port: no read/write permission for us
    port.touch(mode=0o000)
    command = [sys.executable, "-m", "uav_tui", "doctor", "--fc", f"serial://{port}:57600", "--source", "sim:"]
    if os.geteuid() == 0:  # root reads any file: drop that capability for the child
        if shutil.which("setpriv") is None:
            pytest.skip("running as root without setpriv (util-linux): cannot stage a port without permission")
        caps = "-dac_override,-dac_read_search"
        command = ["setpriv", f"--bounding-set={caps}", f"--inh-caps={caps}", *command]
    done = subprocess.run(command, capture_output=True, text=True, timeout=60, cwd=tmp_path,
                          env={**os.environ, "PYTHONPATH": str(ROOT)}, check=False)
    lines = _by_subject(done.stdout)
    assert done.returncode == 1, done.stdout + done.stderr
    assert lines["serial"].startswith("FAIL permission denied") and "dialout" in lines["serial"]


def test_the_pis_console_on_the_autopilots_uart(tmp_path: Path) -> None:
    from controllers.connection import parse_connection
    from uav_tui.field.check_devices import serial_port

    cmdline = tmp_path / "cmdline.txt"
    cmdline.write_text("console=serial0,115200 console=tty1 root=PARTUUID=1 rootwait\n")
    found = serial_port(parse_connection("serial:///dev/serial0:921600"), (cmdline,))
    assert any(f.level.name == "FAIL" and "raspi-config" in f.text for f in found), found
    cmdline.write_text("console=tty1 root=PARTUUID=1 rootwait\n")
    assert not any("console" in f.text for f in serial_port(parse_connection("serial:///dev/serial0:921600"),
                                                                (cmdline,)))


@pytest.mark.parametrize("sim_vehicle", [{"extra_args": ["--offboard-loss-timeout", "9", "--gps-clock-offset",
                                                         "7200"]}], indirect=True)
def test_a_heartbeat_its_failsafe_and_gps_clock(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                               sim_vehicle: SimVehicle) -> None:
    """The simulated PX4 answers: its failsafe is read by the platform's rules (COM_OF_LOSS_T 9 s is too long) and its
    GPS time shows this clock two hours behind."""
    code, lines = _doctor(tmp_path, capsys, f'fc = "{sim_vehicle.connection_string}"\n'
                          "[safety]\ntune_autopilot_failsafe = false\n", "--heartbeat-timeout", "5")
    assert code == 1, lines
    assert lines["heartbeat"].startswith("OK PX4")
    assert "FAIL COM_OF_LOSS_T = 9 flies a stale command for 9 s" in lines["failsafe"]
    assert "FAIL COM_OBL_RC_ACT = 0 is Position mode" in lines["failsafe"]  # no radio on the sim: it sinks
    assert "clock is 2 h behind the autopilot's GPS time" in lines["clock"] or "synchronised" in lines["clock"]


def test_a_config_that_does_not_load_is_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "uav.toml").write_text("max_sped = 2\n")
    assert uav_main(["doctor", "--config", str(tmp_path / "uav.toml")]) == 2
    assert "did you mean 'max_speed'" in capsys.readouterr().err


def test_cameras_are_listed_by_name_and_throttling_is_read(tmp_path: Path) -> None:
    """Which camera is which (the kernel's names, formats bounded when nothing answers), and get_throttled's bits."""
    from uav_tui.config import Config
    from uav_tui.field.check_devices import cameras
    from uav_tui.field.check_host import _throttled

    for number, name in ((0, "HD USB Camera"), (10, "bcm2835-isp")):
        (tmp_path / f"video{number}").mkdir()
        (tmp_path / f"video{number}" / "name").write_text(name + "\n")
    found = cameras(Config(source="usb:0"), tmp_path)
    assert [f.text.split(";")[0] for f in found[:2]] == ["/dev/video0: HD USB Camera", "/dev/video10: bcm2835-isp"]
    assert _throttled(0x50005).level.name == "FAIL" and "under-voltage now" in _throttled(0x50005).text
    assert _throttled(0x50000).level.name == "WARN" and _throttled(0).level.name == "OK"
