"""The operator learns the page's address with the token from ``--no-ui`` output; ``--web`` is a flag."""

from __future__ import annotations

import io
import socket

import pytest

from tests.web.conftest import TOKEN, free_port
from uav_tui.cli import build_parser
from uav_tui.config import load_config, overrides_from_args
from uav_tui.core import CoreState, UavCore
from uav_tui.errors import UavError
from uav_tui.headless import HeadlessRunner


def test_web_flags_reach_the_config() -> None:
    args = build_parser().parse_args(["--web", "--web-port", "8099", "--camera-mavlink", "udpin:0.0.0.0:14580"])
    config = load_config(None, overrides_from_args(args))
    assert config.web.web and config.web.web_port == 8099 and config.web.camera_mavlink == "udpin:0.0.0.0:14580"
    assert not load_config(None).web.web and load_config(None).web.camera_mavlink == ""


async def test_no_ui_prints_the_url_with_the_token() -> None:
    port = free_port()
    config = load_config(None, {"source": "synthetic:", "fc": "none", "record": False, "web": True,
                                "web_host": "127.0.0.1", "web_port": port, "web_token": TOKEN})
    out = io.StringIO()
    runner = HeadlessRunner(config, duration=0.3, out=out)
    assert await runner.run() == 0
    assert f"web page: http://127.0.0.1:{port}/?token={TOKEN}" in out.getvalue().splitlines()


async def test_random_token_when_none_is_configured() -> None:
    tokens = []
    for _ in range(2):
        core = UavCore(load_config(None, {"source": "synthetic:", "fc": "none", "record": False, "web": True,
                                          "web_host": "127.0.0.1", "web_port": free_port()}))
        await core.start()
        tokens.append(core.web.token)
        assert core.web.url.endswith(f"?token={core.web.token}")
        await core.stop()
    assert tokens[0] != tokens[1] and all(len(t) >= 20 for t in tokens)


async def test_busy_port_fails_the_start_and_releases_everything() -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        core = UavCore(load_config(None, {"source": "synthetic:", "fc": "none", "record": False, "web": True,
                                          "web_host": "127.0.0.1", "web_port": port}))
        with pytest.raises(UavError, match="another --web-port"):
            await core.start()
    assert core.state is CoreState.STOPPED
    assert core.source is not None and core.source.get_properties()["running"] is False
