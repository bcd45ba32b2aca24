"""``--fc sim`` takes the simulated vehicle's options (``--home``, ``--wind``, ``--noise``, ``--seed``) as
``uav-tui sim`` does; with another flight controller they are an error, not silently ignored."""

from __future__ import annotations

import asyncio

import pytest

from uav_tui.cli import build_parser
from uav_tui.config import find_config_file, load_config, overrides_from_args
from uav_tui.core import UavCore
from uav_tui.errors import ConfigError


def _config(*flags: str):
    return load_config(find_config_file(None), overrides_from_args(build_parser().parse_args(list(flags))))


async def test_the_flags_reach_the_simulated_vehicle(tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    config = _config("--fc", "sim", "--home", "46.5,7.5,600", "--wind", "1.5,-0.5", "--noise", "--seed", "7",
                     "--no-record", "--source", "synthetic:?width=160&height=120")
    core = UavCore(config)
    await core.start()
    try:
        assert "--noise" in core.controller.sim.command() and core.controller.sim.seed == 7
        truth = core.controller.sim.truth(subscribe=False).request({"cmd": "state"}, timeout=2)["state"]
        assert (truth["wind_n"], truth["wind_e"]) == (1.5, -0.5)
        assert truth["lat"] == pytest.approx(46.5, abs=1e-3) and truth["lon"] == pytest.approx(7.5, abs=1e-3)
        for _ in range(100):
            if (lat := core.telemetry.snapshot().lat_deg) is not None:
                break
            await asyncio.sleep(0.05)
        assert lat == pytest.approx(46.5, abs=1e-3)  # what the autopilot reports, through MAVSDK
    finally:
        await core.stop("test finished")


@pytest.mark.parametrize(("flags", "message"), [
    (("--fc", "none", "--wind", "2,0"), "wind sets up the built-in simulated vehicle, but fc is 'none': use it with "
                                        "--fc sim"),
    (("--fc", "sim", "--wind", "2"), r"--wind: wind must be N,E \(m/s\), got '2'"),
    (("--fc", "sim", "--home", "95,8,400"), "home: home out of range"),
], ids=["not-sim", "wind", "home"])
def test_bad_or_misplaced_settings_name_the_key(tmp_path, monkeypatch, flags, message) -> None:
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ConfigError, match=message):
        _config(*flags)
