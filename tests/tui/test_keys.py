"""Keys without a vehicle (``--fc none``): processor keys, reload, dimmed vehicle keys, help, quit."""

from __future__ import annotations

import shutil
from pathlib import Path

from uav_tui.core import CoreState
from uav_tui.errors import CommandError
from uav_tui.flight.commands import parse
from uav_tui.output.native_stderr import ORIGIN as NATIVE_ORIGIN
from uav_tui.tui.app import KEYS
from uav_tui.tui.screens import ConfirmScreen

from .conftest import HERE, in_log, started, wait_for


def tui_commands(app) -> list[str]:
    """The commands the dashboard sent (the core logs each one, then its result, as command events)."""
    return [e.message for e in app.core.events.recent if e.kind == "command" and e.origin == "tui"
            and e.level == "info" and _is_command(e.message)]


def _is_command(text: str) -> bool:
    try:
        return parse(text) is not None
    except CommandError:
        return False


async def test_function_keys_reach_the_processor(make_app):
    app = make_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        processor = app.core.worker.processor.instance
        for key in ("f2", "f1", "f4", "f3"):
            await pilot.press(key)
        await wait_for(pilot, lambda: len(processor.buttons) == 4, what="four F-keys")
        assert processor.buttons == [2, 1, 4, 3]
        assert tui_commands(app)[:4] == ["f 2", "f 1", "f 4", "f 3"]


async def test_vehicle_keys_are_dimmed_and_do_nothing_without_a_vehicle(make_app):
    app = make_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        bindings = app.screen.active_bindings
        for key in (k for k in KEYS if k.command.split()[0] in ("arm", "takeoff", "land", "hold", "autonomy")):
            assert bindings[key.key][2] is False, key  # (node, binding, enabled, tooltip)
        assert bindings["f1"][2] and bindings["q"][2]
        await pilot.press("a", "h")
        await pilot.pause(0.2)
        assert not isinstance(app.screen, ConfirmScreen)
        assert tui_commands(app) == []


async def test_snapshot_key_sends_the_snapshot_command(make_app):
    app = make_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        await pilot.press("s")
        await wait_for(pilot, lambda: "snapshot" in tui_commands(app), what="snapshot command")


async def test_reload_keeps_the_old_processor_on_a_broken_file_and_loads_a_fixed_one(make_app, tmp_path: Path):
    mine = tmp_path / "mine.py"
    shutil.copy(HERE / "procs.py", mine)
    app = make_app(processor=f"{mine}:RecordingProcessor")
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        old = app.core.worker.processor.instance
        tm = old.tmMgr
        broken_line = len(mine.read_text().splitlines()) + 2
        mine.write_text(mine.read_text() + "\n    def broken(self:\n")
        await pilot.press("R")
        await wait_for(pilot, lambda: in_log(app, "reload failed"), what="the reload error in the log")
        assert in_log(app, f"mine.py:{broken_line}: SyntaxError")
        assert any(n.severity == "error" and "reload failed" in n.message for n in app._notifications)
        frames = old.frames
        await wait_for(pilot, lambda: old.frames > frames + 3, what="the old processor to keep processing")
        assert app.core.worker.processor.instance is old

        shutil.copy(HERE / "procs.py", mine)
        await pilot.press("R")
        await wait_for(pilot, lambda: app.core.worker.processor.instance is not old, what="the new instance")
        new = app.core.worker.processor.instance
        assert new.tmMgr is tm and tm is not None  # the new instance keeps the frame telemetry
        await wait_for(pilot, lambda: new.frames > 0, what="the new processor to process")


async def test_help_key_shows_the_keys(make_app):
    app = make_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        await pilot.press("question_mark")
        await pilot.pause(0.1)
        assert app.screen.query("HelpPanel")
        await pilot.press("escape")
        await pilot.pause(0.1)
        assert not app.screen.query("HelpPanel")  # Esc closes it, as it closes every other panel


async def test_quit_key_stops_the_core_and_exits(make_app):
    app = make_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        await pilot.press("q")
        await wait_for(pilot, lambda: app.core.state is CoreState.STOPPED, what="the core to stop")
        await wait_for(pilot, lambda: not app.is_running, what="the app to exit")
    assert app.return_code == 0


async def test_a_processor_that_cannot_load_ends_the_app_with_file_and_line(make_app, tmp_path: Path):
    broken = tmp_path / "broken.py"
    broken.write_text("import numpy\n\nclass Broken:\n    def photo_processing(self, frame)\n        pass\n")
    app = make_app(processor=f"{broken}:Broken")
    async with app.run_test(size=(80, 24)) as pilot:
        await wait_for(pilot, lambda: not app.is_running, what="the app to exit")
    assert app.return_code == 2
    assert f"{broken}:4" in app.start_error and "SyntaxError" in app.start_error


async def test_typed_commands_go_the_same_way_and_typos_are_shown(make_app):
    app = make_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        await pilot.press("colon", *"f 4", "enter")
        processor = app.core.worker.processor.instance
        await wait_for(pilot, lambda: processor.buttons == [4], what="the typed F4")
        await pilot.press("colon", *"fly away", "enter")
        await wait_for(pilot, lambda: in_log(app, "unknown command 'fly'"), what="the typo in the log")
        await pilot.press("colon", *"f 1", "escape")
        await pilot.pause(0.2)
        assert processor.buttons == [4] and app.is_running


async def test_the_dashboard_shows_the_page_url_with_its_token_but_never_records_it(make_app):
    from tests.web.conftest import TOKEN, free_port

    app = make_app(web=True, web_host="127.0.0.1", web_port=free_port(), web_token=TOKEN)
    async with app.run_test(size=(120, 40)) as pilot:
        await started(pilot)
        url = app.core.web.url
        await wait_for(pilot, lambda: in_log(app, f"web page: {url}"), what="the page's URL in the event log")
        assert TOKEN in url
        assert not [e for e in app.core.events.recent if TOKEN in e.message]
        assert not [e for e in app.core.events.recent if "token=" in e.message]  # not even redacted (#47)
        assert any(e.message.startswith(f"web page on {url.partition('?')[0]}") for e in app.core.events.recent)


async def test_native_library_lines_are_logged_without_popping_up(make_app):
    app = make_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        app.clear_notifications()
        for n in range(30):  # a decoder's burst: it would cover the screen with pop-ups
            app.core.events.emit("warning", "platform", f"native library: [h264 @ 0x1] error {n}", NATIVE_ORIGIN)
        app.core.events.emit("warning", "platform", "a warning of the platform's own")
        await wait_for(pilot, lambda: list(app._notifications), what="the pop-up of the platform's warning")
        assert [n.message for n in app._notifications] == ["a warning of the platform's own"]
        assert in_log(app, "native library: [h264 @ 0x1] error 29")


async def test_what_the_processor_prints_is_in_the_log_and_a_flood_is_bounded(make_app):
    app = make_app(processor=f"{HERE / 'procs.py'}:PrintingProcessor")
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        # Before: print() under the dashboard went nowhere.
        await wait_for(pilot, lambda: in_log(app, "print: hello from the processor, frame 30"), what="a print")
        await pilot.press("f1")
        await wait_for(pilot, lambda: in_log(app, "more printed lines not shown (too many at once)"), timeout=5,
                       what="the count of the lines left out")
        shown = [strip.text for strip in app.query_one("#events").lines]
        assert any("print: \\x1b[2Jcleared?" in line for line in shown), shown  # escaped: it cannot clear the screen
        assert not any("\x1b" in line for line in shown)
        assert sum("print: line " in line for line in shown) < 25  # a burst of 20, then about one a second
