"""``uav-tui service``: the unit systemd accepts, and its command line run the way systemd runs it."""

from __future__ import annotations

import csv
import os
import re
import shutil
import signal
import subprocess
import time
from pathlib import Path

import pytest

from uav_tui.cli import main as uav_main
from uav_tui.field.unit import exec_start

ROOT = Path(__file__).resolve().parents[2]
SYSTEMD_PATH = "/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"
"""The PATH systemd gives a service."""


def _config(tmp_path: Path, text: str = "") -> Path:
    path = tmp_path / "uav.toml"
    path.write_text(f'fc = "sim"\nsource = "sim:"\n{text}', encoding="utf-8")
    return path


def _install(tmp_path: Path, *flags: str) -> Path:
    units = tmp_path / "units"
    code = uav_main(["service", "install", "--config", str(_config(tmp_path, '[recording]\nruns_dir = "runs"\n'
                                                                    "record_every = 3\n")),
                     "--unit-dir", str(units), "--working-dir", str(tmp_path), "--no-systemctl", *flags])
    assert code == 0
    return units / "uav-tui.service"


@pytest.mark.parametrize("flags", [(), ("--system", "--run-as", "root")], ids=["user", "system"])
def test_the_unit_passes_systemd_analyze_verify(tmp_path: Path, flags: tuple[str, ...]) -> None:
    analyze = shutil.which("systemd-analyze")
    if analyze is None:
        pytest.skip("systemd-analyze is not installed (apt install systemd)")
    unit = _install(tmp_path, *flags)
    done = subprocess.run([analyze, "verify", str(unit)], capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 0, done.stderr
    assert str(unit) not in done.stderr  # systemd 252 only warns, exit 0, on an unknown key: no warning at all
    text = unit.read_text()
    assert ("SupplementaryGroups=dialout" in text and "User=root" in text) == bool(flags)
    assert "--script" not in text and "StartLimitBurst=" in text and "RestartSec=" in text


def test_without_systemctl_install_status_and_remove_say_what_to_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                     capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))  # no systemctl, journalctl, loginctl on it
    units = tmp_path / "units"
    code = uav_main(["service", "install", "--config", str(_config(tmp_path)), "--unit-dir", str(units)])
    out = capsys.readouterr().out
    assert code == 0 and (units / "uav-tui.service").is_file()
    assert "systemctl not found" in out and "systemctl --user daemon-reload; systemctl --user enable" in out
    assert "sudo loginctl enable-linger" in out
    assert uav_main(["service", "status", "--unit-dir", str(units)]) == 0
    out = capsys.readouterr().out
    assert f"installed: {units / 'uav-tui.service'}" in out and "--no-ui --config" in out
    assert uav_main(["service", "remove", "--unit-dir", str(units)]) == 0
    assert "systemctl --user disable --now uav-tui.service" in capsys.readouterr().out
    assert not (units / "uav-tui.service").exists()
    assert uav_main(["service", "status", "--unit-dir", str(units)]) == 1
    assert "not installed" in capsys.readouterr().out


def test_a_config_that_would_not_start_is_refused_at_install(tmp_path: Path,
                                                             capsys: pytest.CaptureFixture[str]) -> None:
    config = _config(tmp_path, "max_sped = 2\n")
    assert uav_main(["service", "install", "--config", str(config), "--unit-dir", str(tmp_path / "u"),
                     "--no-systemctl"]) == 2
    assert "unknown key 'max_sped'" in capsys.readouterr().err
    assert not (tmp_path / "u").exists()


@pytest.mark.timeout(180)
def test_the_units_command_starts_records_stops_on_sigterm_and_never_flies(tmp_path: Path) -> None:
    """As systemd runs it: ExecStart in WorkingDirectory, stdin /dev/null, no terminal (a session of its own), only
    the unit's environment and systemd's PATH. The harness adds PYTHONPATH, so the code under test is this tree's."""
    unit = _install(tmp_path)
    text = unit.read_text()
    env = {"PATH": SYSTEMD_PATH, "PYTHONPATH": str(ROOT)}
    env |= dict(line.removeprefix("Environment=").split("=", 1) for line in text.splitlines()
                if line.startswith("Environment="))
    log = (tmp_path / "journal.txt").open("w")
    process = subprocess.Popen(exec_start(text), cwd=tmp_path, env=env, stdin=subprocess.DEVNULL, stdout=log,
                               stderr=subprocess.STDOUT, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while not (list((tmp_path / "runs").glob("*/frames/*.jpg")) and len(_vehicle_lines(tmp_path)) >= 3):
            assert time.monotonic() < deadline and process.poll() is None, "no frame or vehicle state recorded"
            time.sleep(0.5)
        assert process.poll() is None, (tmp_path / "journal.txt").read_text()
        process.send_signal(signal.SIGTERM)
        assert process.wait(timeout=60) == 0, (tmp_path / "journal.txt").read_text()
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
        log.close()
    (run,) = (tmp_path / "runs").iterdir()
    with (run / "telemetry.csv").open() as file:
        rows = list(csv.DictReader(file))
    assert "False" in {row["armed"] for row in rows} <= {"False", ""}  # known, and never armed
    assert all(" disarmed" in line and "auto OFF" in line for line in _vehicle_lines(tmp_path))
    assert "stopped: SIGTERM" in (tmp_path / "journal.txt").read_text()


def _vehicle_lines(tmp_path: Path) -> list[str]:
    """The status lines with the vehicle's state (its flight mode known) in the unit's log."""
    return re.findall(r".* hb [0-9.]+s (?!\?)\S+ .*", (tmp_path / "journal.txt").read_text())


def test_a_system_unit_names_its_user(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    """Run with sudo, the unit runs as the user who ran sudo; as plain root, it asks for --run-as."""
    monkeypatch.setattr("getpass.getuser", lambda: "root")
    monkeypatch.delenv("SUDO_USER", raising=False)
    flags = ["service", "install", "--system", "--config", str(_config(tmp_path)), "--unit-dir", str(tmp_path / "u"),
             "--no-systemctl"]
    assert uav_main(flags) == 2 and "--run-as USER" in capsys.readouterr().err
    monkeypatch.setenv("SUDO_USER", "pi")
    assert uav_main(flags) == 0
    assert "User=pi\n" in (tmp_path / "u" / "uav-tui.service").read_text()


@pytest.mark.parametrize("name", ["../escape", "a\nExecStartPre=/bin/sh", "%h", ".hidden"],
                         ids=["folder", "new line", "specifier", "dot"])
def test_a_unit_name_that_is_no_name_is_refused(tmp_path: Path, name: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exited:
        uav_main(["service", "install", "--name", name, "--config", str(_config(tmp_path)),
                  "--unit-dir", str(tmp_path / "u"), "--no-systemctl"])
    assert exited.value.code == 2 and "is not a unit name" in capsys.readouterr().err
    assert not (tmp_path / "u").exists() and not (tmp_path / "escape.service").exists()


def test_a_percent_in_the_working_folder_is_no_specifier(tmp_path: Path) -> None:
    folder = tmp_path / "runs 100%h"
    folder.mkdir()
    units = tmp_path / "units"
    assert uav_main(["service", "install", "--config", str(_config(tmp_path)), "--unit-dir", str(units),
                     "--working-dir", str(folder), "--no-systemctl"]) == 0
    assert f"WorkingDirectory={tmp_path}/runs 100%%h\n" in (units / "uav-tui.service").read_text()
