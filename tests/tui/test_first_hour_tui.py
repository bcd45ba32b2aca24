"""The dashboard's first-hour stumbles (#46) on an 80x24 terminal: what F1-F4 and ``?`` say, autonomy for a
processor with nothing to fly, a print flood (the quit question once the vehicle disarmed: test_vehicle.py)."""

from __future__ import annotations

import io
import time
from collections import Counter

from rich.console import Console
from textual.message import Message
from textual.widgets._key_panel import BindingsTable

from uav_tui.output.line_budget import BURST_LINES, LINES_PER_S

from .conftest import HERE, in_log, started, wait_for


async def test_f_keys_say_what_the_button_means_and_help_lists_keys_as_the_bar_names_them(make_app):
    app = make_app(processor=f"{HERE / 'procs.py'}:DescribedButtons")
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        await pilot.press("f1", "f2")
        await wait_for(pilot, lambda: in_log(app, "F1 mark the spot: DescribedButtons.customize_processing(1) done")
                       and in_log(app, "F2: DescribedButtons.customize_processing(2) done"), what="both F-keys")
        await pilot.press("question_mark")
        await pilot.pause(0.3)
        console = Console(width=100, file=io.StringIO(), record=True)
        console.print(app.screen.query_one(BindingsTable).render_bindings_table())  # the help, unwrapped
        rows = [" ".join(line.split()) for line in console.export_text().splitlines()]
    assert "F1 mark the spot" in rows and "F3 forget the spot" in rows, rows  # before: "f1 F1"
    assert "F2 processor button 2" in rows and "? Help" in rows and ": Command" in rows, rows


async def test_autonomy_for_a_processor_without_a_vector_is_refused_naming_the_typo(make_app):
    app = make_app(fc="sim", processor=f"{HERE / 'procs.py'}:MisspeltVector")
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        assert in_log(app, "MisspeltVector.getPreparedVectr is not a name the platform calls: did you mean "
                           "getPreparedVector?")  # said at load
        await pilot.press("g")
        await wait_for(pilot, lambda: in_log(app, "autonomy refused: processor"), what="the refusal")
        assert not app.core.gate.enabled  # before: autonomy ON
        assert in_log(app, "has no getPreparedVector() (nor getLandingTarget() or getGimbalPointing()), so it gives "
                           "the vehicle nothing to fly")


async def test_a_print_flood_queues_no_more_than_the_budget_on_the_loop(make_app):
    app = make_app(processor=f"{HERE / 'procs.py'}:Flooding", processor_call_timeout=60)
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        log = app.query_one("#events")
        queued: Counter[str] = Counter()
        put = log._message_queue.put_nowait  # every message to the log passes here, each held until taken

        def counted(message: Message) -> None:
            queued[type(message).__name__] += 1
            put(message)

        log._message_queue.put_nowait = counted
        started_s = time.monotonic()
        await app.core.execute("f 4", origin="test")  # returns once the processor's 20,000 prints are done
        await wait_for(pilot, lambda: in_log(app, "more printed lines not shown (too many at once)"),
                       what="the count of the lines left out")
        # The budget's own rule: a burst, then a line and a count a second, however long the flood took here.
        budget = BURST_LINES + 2 * LINES_PER_S * (time.monotonic() - started_s + 1)
    printed = queued["Print"] + queued["Printed"]
    assert printed <= budget, queued  # before: a Print per write, 40,000, however fast the log took them
