"""rtsp:// and http:// streams against real servers on loopback, including a killed and restarted stream."""

from __future__ import annotations

import os
import socket
import time

import pytest

from controllers.sim.launcher import free_ports
from sources import create_source, open_source
from sources.network import OPTIONS_ENV, NetworkSource, redact
from uav_tui.errors import SourceError


def _wait_for(condition, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.05)
    return False


@pytest.mark.parametrize("server_fixture", ["rtsp_server", "mjpeg_server"], ids=["rtsp", "http-mjpeg"])
def test_recovers_by_itself_when_the_stream_is_killed_and_restarted(server_fixture: str, request, fast_retry) -> None:
    server = request.getfixturevalue(server_fixture)
    source = open_source(server.url)
    try:
        assert source.buffer.wait_newer(2, timeout=10) is not None
        server.stop()
        assert _wait_for(lambda: source.get_properties()["stalled_since"] is not None, timeout=10)
        stalled_at = source.get_properties()["frames_captured"]
        time.sleep(0.5)
        server.start()
        frame = source.buffer.wait_newer(stalled_at + 3, timeout=20)
        assert frame is not None, source.get_properties()
        props = source.get_properties()
        assert props["stalled_since"] is None and props["errors"] >= 1
        assert props["last_error"]  # the outage stays visible after recovery
    finally:
        source.close()


def test_a_hung_stream_is_detected_by_the_read_timeout(mjpeg_server, fast_retry) -> None:
    source = NetworkSource(mjpeg_server.url, read_timeout_s=1.0)
    assert source.open()
    try:
        assert source.buffer.wait_newer(2, timeout=10) is not None
        mjpeg_server.frozen.set()  # the connection stays open, nothing arrives
        assert _wait_for(lambda: source.get_properties()["stalled_since"] is not None, timeout=8)
        stalled_at = source.get_properties()["frames_captured"]
        mjpeg_server.frozen.clear()
        assert source.buffer.wait_newer(stalled_at + 2, timeout=15) is not None, source.get_properties()
        assert source.get_properties()["stalled_since"] is None
    finally:
        source.close()


def test_rtsp_properties_and_low_latency_options(rtsp_server) -> None:
    source = open_source(rtsp_server.url)
    try:
        props = source.get_properties()
        assert props["kind"] == "rtsp" and props["url"] == rtsp_server.url
        assert (props["width"], props["height"], props["fps"]) == (320, 240, 15)
        assert "rtsp_transport;tcp" in props["ffmpeg_options"] and "fflags;nobuffer" in props["ffmpeg_options"]
        assert OPTIONS_ENV not in os.environ  # set only while opening
    finally:
        source.close()


def test_users_own_ffmpeg_options_win(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(OPTIONS_ENV, "rtsp_transport;udp")
    assert create_source("rtsp://127.0.0.1:1/x").get_properties()["ffmpeg_options"] == "rtsp_transport;udp"


def test_nothing_listening_fails_to_open_with_advice() -> None:
    source = NetworkSource(f"rtsp://127.0.0.1:{free_ports(1, socket.SOCK_STREAM)[0]}/live", open_timeout_s=2)
    started = time.monotonic()
    assert source.open() is False
    assert time.monotonic() - started < 5
    error = source.get_properties()["last_error"]
    assert "did not open (failed after 0." in error and "is the server up" in error  # not "within 2 s"
    source.close()


def test_credentials_never_show() -> None:
    url = "rtsp://admin:s3cret@192.0.2.10:554/stream1"
    assert redact(url) == "rtsp://admin:***@192.0.2.10:554/stream1"
    source = create_source(url)
    assert "s3cret" not in repr(source.get_properties()) and "s3cret" not in repr(source)
    assert source.url == url


def test_url_without_host_is_rejected() -> None:
    with pytest.raises(SourceError, match="no host"):
        create_source("rtsp:///stream")
