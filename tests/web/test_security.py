"""What someone on the drone's network can try (issue 14, points 6-10), against the real server."""

from __future__ import annotations

import asyncio
import csv
import io
import json
import os
import secrets
import subprocess
import sys
from pathlib import Path

import aiohttp
import pytest
from yarl import URL

from tests.sources.stream_servers import RtspTestServer
from tests.web.conftest import TOKEN, free_port, make_core, processor_of
from uav_tui.config import load_config
from uav_tui.core import UavCore
from uav_tui.errors import ConfigError
from uav_tui.flight.commands import parse
from uav_tui.headless import HeadlessRunner
from uav_tui.web.throttle import AuthThrottle

FORGED_PATH = "/%1B%5B2J%1B%5BH%1B%5D0;pwned%07%0A[info]%20command:%20arm%0D%0A[info]%20command:%20takeoff"
"""Clears the screen, retitles the terminal and forges two event lines, once percent-decoded."""


def base(core: UavCore) -> str:
    return f"http://127.0.0.1:{core.web.port}"


async def start_headless(config_overrides: dict, script: list | None = None) -> tuple[HeadlessRunner, io.StringIO,
                                                                                      asyncio.Task[int]]:
    settings = {"source": "synthetic:?width=160&height=120", "fc": "none", "web": True, "web_host": "127.0.0.1",
                "web_port": free_port(), "web_token": TOKEN, **config_overrides}
    out = io.StringIO()
    runner = HeadlessRunner(load_config(None, settings), out=out, script=script)
    task = asyncio.create_task(runner.run())
    for _ in range(400):
        if runner.core.web is not None and "web page:" in out.getvalue():
            break
        await asyncio.sleep(0.05)
    assert runner.core.web is not None, out.getvalue()
    return runner, out, task


def events_csv(core: UavCore) -> str:
    return (core.recorder.run_dir / "events.csv").read_text()


# -- 7: nothing from outside writes to the operator's terminal, log or CSV ---------------------------


async def test_a_request_path_cannot_clear_the_screen_or_forge_a_line(tmp_path: Path) -> None:
    runner, out, task = await start_headless({"runs_dir": str(tmp_path)})
    core = runner.core
    async with aiohttp.ClientSession() as http:
        async with http.get(URL(base(core) + FORGED_PATH, encoded=True)) as response:
            assert response.status == 401
        async with http.get(URL(base(core) + FORGED_PATH, encoded=True), params={"token": TOKEN}) as response:
            assert response.status == 404
    runner.request_stop("test finished")
    assert await task == 0
    printed, recorded = out.getvalue(), events_csv(core)
    for text in (printed, recorded):
        assert "\x1b" not in text and "\x07" not in text and "\r" not in text
        assert not [line for line in text.splitlines() if "command: arm" in line and "refused" not in line]
    assert "refused GET '/\\x1b[2J\\x1b[H\\x1b]0;pwned\\x07\\n[info] command: arm" in printed
    messages = [row["message"] for row in csv.DictReader(io.StringIO(recorded))]
    assert any(m.startswith("refused GET '/\\x1b[2J") for m in messages)


# -- 8: credentials and the token are never printed or recorded -------------------------------------


async def test_passwords_and_the_token_stay_out_of_outputs_and_records(tmp_path: Path) -> None:
    server = RtspTestServer()
    server.start()
    try:
        secret_uri = f"rtsp://admin:Hunter2pw@127.0.0.1:{server.port}/live"
        script = [(1, parse("wait 1.2")), (2, parse(f"source {secret_uri}")), (3, parse("wait 1.2"))]
        runner, out, task = await start_headless({"runs_dir": str(tmp_path), "source": secret_uri}, script)
        core = runner.core
        for _ in range(400):
            if "camera switched" in out.getvalue():
                break
            await asyncio.sleep(0.05)
        status = json.dumps(core.status().as_dict(), default=str)  # what the web page and --json show
        assert await asyncio.wait_for(task, 60) == 0
    finally:
        server.stop()
    printed = out.getvalue()
    run_json = (core.recorder.run_dir / "run.json").read_text()
    recorded = events_csv(core)
    assert "camera switched to rtsp://admin:***@127.0.0.1" in recorded and "rtsp://admin:***@" in run_json
    assert "command: source rtsp://admin:***@127.0.0.1" in printed and "rtsp://admin:***@" in status
    for text in (printed, run_json, recorded, status):
        assert "Hunter2pw" not in text
    for text in (run_json, recorded):
        assert TOKEN not in text
    assert f"web page: http://127.0.0.1:{core.web.port}/?token={TOKEN}" in printed  # only there, for the operator


async def test_passwords_with_any_character_and_secret_parameters_stay_out_of_outputs(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Issue 42 point 4: the usual secret query parameters, and a password holding a ``/``, through every output."""
    server = RtspTestServer()
    server.start()
    try:
        query_uri = f"rtsp://127.0.0.1:{server.port}/live?pwd=Leak3&pass=Leak4&passwd=Leak5&api_key=Leak6&channel=1"
        slash_uri = f"rtsp://admin:Leak2/pw@127.0.0.1:{server.port}/live"  # FFmpeg cannot open it: said in errors
        script = [(1, parse("wait 1.0")), (2, parse(f"source {slash_uri}"))]
        runner, out, task = await start_headless({"runs_dir": str(tmp_path), "source": query_uri}, script)
        core = runner.core
        status = json.dumps(core.status().as_dict(), default=str)  # what the web page, --json and the TUI show
        assert await asyncio.wait_for(task, 60) == 1  # the script's source command failed
    finally:
        server.stop()
    printed, recorded = out.getvalue() + capsys.readouterr().err, events_csv(core)
    run_json = (core.recorder.run_dir / "run.json").read_text()
    assert "source rtsp://admin:***@127.0.0.1" in printed and "source rtsp://admin:***@127.0.0.1" in recorded
    assert "?pwd=***&pass=***&passwd=***&api_key=***&channel=1" in run_json
    assert "pwd=***" in status and "pwd=***" in recorded
    for text in (printed, recorded, run_json, status):
        for secret in ("Leak2", "pw@", "Leak3", "Leak4", "Leak5", "Leak6"):
            assert secret not in text


# -- 9: a token worth guessing, and guessing slowed -------------------------------------------------


@pytest.mark.parametrize("token", ["k7", "a" * 16, "x" * 40, "test-token-0123456789", "password1234567890",
                                   "abcdefghijklmnopqrstuvwxyz"], ids=["short", "one-letter", "long-one-letter",
                                                                       "words-and-digits", "common", "sequence"])
def test_a_guessable_token_is_a_config_error_saying_how_to_make_one(tmp_path: Path, token: str) -> None:
    (tmp_path / "uav.toml").write_text(f'[web]\nweb_token = "{token}"\n')
    for where, load in (("web.web_token", lambda: load_config(tmp_path / "uav.toml")),
                        ("--web-token", lambda: load_config(None, {"web_token": token}))):
        with pytest.raises(ConfigError, match="bits of entropy estimated, at least 96") as refused:
            load()
        assert f"{where} is too easy to guess" in str(refused.value) and "token_urlsafe(24)" in str(refused.value)


def test_a_random_token_is_accepted() -> None:
    for token in (TOKEN, secrets.token_urlsafe(24), secrets.token_hex(16)):
        assert load_config(None, {"web_token": token}).web.web_token == token


def test_uav_tui_refuses_to_serve_the_page_with_a_one_letter_token(tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
    run = subprocess.run([sys.executable, "-m", "uav_tui", "--no-ui", "--fc", "none", "--source", "synthetic:",
                          "--no-record", "--web", "--web-host", "127.0.0.1", "--web-port", str(free_port()),
                          "--web-token", "a" * 16, "--duration", "3"], cwd=tmp_path, env=env, capture_output=True,
                         text=True, timeout=60)
    assert run.returncode == 2 and "web page:" not in run.stdout
    assert 'python3 -c "import secrets; print(secrets.token_urlsafe(24))"' in run.stderr, run.stderr


def test_the_throttle_grows_is_bounded_and_forgets() -> None:
    now = [0.0]
    throttle = AuthThrottle(free=3, base_s=1.0, max_delay_s=8.0, forget_s=60.0, clock=lambda: now[0])
    assert [throttle.failed("a") for _ in range(3)] == [0.0, 0.0, 0.0]
    delays = []
    for _ in range(6):
        delays.append(throttle.failed("a"))
        assert throttle.retry_after("a") == delays[-1] and throttle.retry_after("b") == 0
        now[0] += delays[-1]
    assert delays == [1.0, 2.0, 4.0, 1.0, 0.0, 0.0]  # never more than 8 s in a row, then open for 2 s
    now[0] += 2.1
    assert throttle.failed("a") == 8.0  # the blocks start again
    now[0] += 61  # a quiet minute: forgotten
    assert throttle.failed("a") == 0.0
    throttle.succeeded("a")
    assert throttle.retry_after("a") == 0
    crowd = AuthThrottle(max_clients=10, clock=lambda: now[0])
    for n in range(1000):
        crowd.failed(f"10.0.{n // 256}.{n % 256}")
    assert len(crowd._clients) == 10


async def test_guessing_gets_429_with_retry_after_then_the_operator_gets_in(web_core: UavCore) -> None:
    statuses, retry = [], []
    async with aiohttp.ClientSession() as http:
        for n in range(8):
            async with http.get(base(web_core) + "/", params={"token": f"guess-{n}"}) as response:
                statuses.append(response.status)
                retry.append(response.headers.get("Retry-After"))
        assert statuses == [401] * 6 + [429, 429] and retry[6] == "1"
        async with http.get(web_core.web.url) as response:  # even the right token waits out the block
            assert response.status == 429
        await asyncio.sleep(1.1)
        async with http.get(base(web_core) + "/", params={"token": "guess-again"}) as response:
            assert response.status == 401  # the next failure doubles the block
        async with http.get(base(web_core) + "/", params={"token": TOKEN}) as response:
            assert response.status == 429 and response.headers["Retry-After"] == "2"
        await asyncio.sleep(2.1)
        async with http.get(web_core.web.url) as response:
            assert response.status == 200
    assert processor_of(web_core).buttons == []


# -- 10: other sites' pages cannot send commands ----------------------------------------------------


@pytest.mark.parametrize("origin", ["http://evil.example", "null", "http://127.0.0.1:1"])
async def test_a_foreign_origin_cannot_post_or_open_the_websocket(web_core: UavCore, origin: str) -> None:
    headers = {"Authorization": f"Bearer {TOKEN}", "Origin": origin}
    async with aiohttp.ClientSession() as http:
        for path, body in (("/api/command", {"command": "f 2"}), ("/api/roi", {"point": [0.5, 0.5]}),
                           ("/offer", {"sdp": "v=0", "type": "offer"})):
            async with http.post(base(web_core) + path, json=body, headers=headers) as response:
                assert response.status == 403, path
                assert "web_origins" in await response.text()
        with pytest.raises(aiohttp.WSServerHandshakeError) as refused:
            await http.ws_connect(base(web_core) + "/ws", params={"token": TOKEN}, headers={"Origin": origin})
        assert refused.value.status == 403
        same = {"Authorization": f"Bearer {TOKEN}", "Origin": base(web_core)}
        async with http.post(base(web_core) + "/api/command", json={"command": "f 3"}, headers=same) as response:
            assert response.status == 200
    assert processor_of(web_core).buttons == [3] and processor_of(web_core).rois == []
    assert any("not allowed" in e.message for e in web_core.events.recent if e.kind == "web")


async def test_configured_origins_are_allowed() -> None:
    core = make_core(web_origins="https://gcs.local:8443, http://laptop:9000/")
    await core.start()
    try:
        async with aiohttp.ClientSession() as http:
            for origin, status in (("https://gcs.local:8443", 200), ("http://laptop:9000", 200),
                                   ("http://laptop:9001", 403)):
                headers = {"Authorization": f"Bearer {TOKEN}", "Origin": origin}
                async with http.post(base(core) + "/api/command", json={"command": "f 1"},
                                     headers=headers) as response:
                    assert response.status == status, origin
        assert processor_of(core).buttons == [1, 1]
    finally:
        await core.stop("test finished")


# -- 6: impossible values from the page are a 400, not a 500 ----------------------------------------


@pytest.mark.parametrize("body", [
    json.dumps({"command": "roi inf 0 1 1"}).encode(),
    json.dumps({"command": "roi 1e999 0 10 10"}).encode(),
    b'{"command": ' + b"[" * 5000 + b"]" * 5000 + b"}",
    b"[" * 100_000 + b"]" * 100_000,
    b'{"command": "f 1\xff"}',
], ids=["roi-inf", "roi-overflow", "nested-5000", "nested-100000", "not-utf8"])
async def test_impossible_values_are_400_with_a_clear_message(web_core: UavCore, body: bytes) -> None:
    async with aiohttp.ClientSession() as http, http.post(
            base(web_core) + "/api/command", params={"token": TOKEN}, data=body) as response:
        assert response.status == 400
        text = await response.text()
        assert "not a finite number; usage: roi X Y W H" in text or "not a JSON object" in text
    async with aiohttp.ClientSession() as http, http.post(
            base(web_core) + "/api/command", params={"token": TOKEN}, json={"command": "f 4"}) as response:
        assert response.status == 200  # and the page still works
    assert processor_of(web_core).buttons == [4] and processor_of(web_core).rois == []


@pytest.mark.parametrize("body", [{"rect": [10**400, 0, 1, 1]}, {"point": [0.5, -(10**400)]}],
                         ids=["rect-huge-int", "point-huge-int"])
async def test_an_impossible_selection_is_400_and_selecting_still_works(web_core: UavCore, body: dict) -> None:
    async with aiohttp.ClientSession() as http:
        async with http.post(base(web_core) + "/api/roi", params={"token": TOKEN}, json=body) as response:
            assert response.status == 400
            assert "is not a number in 0..1" in await response.text()
        async with http.post(base(web_core) + "/api/roi", params={"token": TOKEN},
                             json={"point": [0.5, 0.5]}) as response:
            assert response.status == 200
    assert processor_of(web_core).rois == [(296, 216, 48, 48)]


async def test_a_handler_bug_is_a_500_logged_once_and_the_page_goes_on(
        web_core: UavCore, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture) -> None:
    def bug(*args: object) -> None:
        raise RuntimeError("a bug in the route")

    monkeypatch.setattr("uav_tui.web.server.roi_from_message", bug)
    async with aiohttp.ClientSession() as http:
        for _ in range(5):
            async with http.post(base(web_core) + "/api/roi", params={"token": TOKEN},
                                 json={"point": [0.5, 0.5]}) as response:
                assert response.status == 500 and "a bug, logged" in await response.text()
        monkeypatch.undo()
        async with http.post(base(web_core) + "/api/roi", params={"token": TOKEN},
                             json={"point": [0.5, 0.5]}) as response:
            assert response.status == 200
    assert processor_of(web_core).rois == [(296, 216, 48, 48)]
    assert len([r for r in caplog.records if r.exc_info and "a bug in the route" in str(r.exc_info[1])]) == 1
    said = [e.message for e in web_core.events.recent if "a bug in the route" in e.message]
    assert len(said) == 3 and said[0].startswith("web page: POST '/api/roi' from web:127.0.0.1 failed")


async def test_a_flood_of_bad_requests_is_counted_not_logged_each(web_core: UavCore) -> None:
    async with aiohttp.ClientSession() as http:
        for _ in range(200):
            async with http.post(base(web_core) + "/api/command", params={"token": TOKEN}, data=b"{") as response:
                assert response.status == 400
    await web_core.web.stop()  # says the count
    said = [e.message for e in web_core.events.recent if e.kind == "web" and e.level == "warning"]
    refused = [m for m in said if "not a JSON object" in m]
    assert 1 <= len(refused) <= 25
    counted = sum(int(m.split()[0]) for m in said if m.endswith("more bad requests refused"))
    assert len(refused) + counted == 200
