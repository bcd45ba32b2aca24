"""Keys with the simulated vehicle (``--fc sim``): confirmations, every vehicle key, autonomy, quit while armed."""

from __future__ import annotations

from textual.widgets import Label

from uav_tui.core import CoreState
from uav_tui.tui._header import AutonomyBadge, VehicleLine
from uav_tui.tui.screens import ConfirmScreen

from .conftest import HERE, in_log, started, wait_for
from .test_keys import tui_commands


def armed(app) -> bool:
    return bool(app.core.telemetry.snapshot().armed)


def header_text(app) -> str:
    return str(app.query_one(VehicleLine).render())


async def test_arm_asks_first_then_arms_and_the_header_says_so(make_app):
    app = make_app(fc="sim")
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        await wait_for(pilot, lambda: "disarmed" in header_text(app), what="telemetry in the header")
        await pilot.press("a")
        assert isinstance(app.screen, ConfirmScreen)
        await pilot.press("escape")  # cancel: nothing is sent
        assert not isinstance(app.screen, ConfirmScreen)
        await pilot.pause(0.3)
        assert "arm" not in tui_commands(app) and not armed(app)

        await pilot.press("a")
        await pilot.press("y")
        await wait_for(pilot, lambda: armed(app), what="the vehicle to arm")
        await wait_for(pilot, lambda: "ARMED" in header_text(app), what="ARMED in the header")

        for key, command in (("h", "hold"), ("l", "land")):  # never confirmed
            await pilot.press(key)
            assert not isinstance(app.screen, ConfirmScreen)
            await wait_for(pilot, lambda command=command: command in tui_commands(app), what=command)


async def test_takeoff_and_disarm_ask_first(make_app):
    app = make_app(fc="sim")
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        for key in ("t", "d"):
            await pilot.press(key)
            assert isinstance(app.screen, ConfirmScreen), key
            await pilot.press("n")
        await pilot.press("d", "y")
        await wait_for(pilot, lambda: "disarm" in tui_commands(app), what="disarm")
        assert "takeoff" not in tui_commands(app)
        await pilot.press("r", "o")  # sent at once (on the ground the autopilot may refuse: shown, not raised)
        assert not isinstance(app.screen, ConfirmScreen)
        await wait_for(pilot, lambda: {"rtl", "orbit 10.0 2.0"} <= set(tui_commands(app)), what="rtl and orbit")


async def test_autonomy_key_toggles_the_badge(make_app):
    app = make_app(fc="sim", processor=f"{HERE / 'procs.py'}:SteeringProcessor")
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        badge = app.query_one(AutonomyBadge)
        await pilot.press("g")
        await wait_for(pilot, lambda: badge.on and app.core.gate.enabled, what="autonomy ON")
        assert "ON" in str(badge.render()) and badge.has_class("-on")
        assert in_log(app, "autonomy ON")
        await pilot.press("g")
        await wait_for(pilot, lambda: not badge.on and not app.core.gate.enabled, what="autonomy OFF")


async def test_quit_while_armed_asks_and_stops_the_core(make_app):
    app = make_app(fc="sim")
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        await pilot.press("a", "y")
        await wait_for(pilot, lambda: armed(app), what="the vehicle to arm")
        await pilot.press("q")
        assert isinstance(app.screen, ConfirmScreen)
        await pilot.press("n")
        await pilot.pause(0.3)
        assert app.is_running and app.core.state is CoreState.RUNNING
        await pilot.press("q")
        question = app.screen.query_one("#question", Label)
        assert str(question.render()).startswith("The vehicle is ARMED. Quit?")
        await app.core.execute("disarm", origin="test")  # the pilot's switch, the autopilot's auto-disarm
        await wait_for(pilot, lambda: str(question.render()) == "The vehicle is disarmed now. Quit?",
                       what="the question to follow the vehicle")  # #46; before: still "ARMED"
        await pilot.press("y")
        await wait_for(pilot, lambda: app.core.state is CoreState.STOPPED, what="the core to stop")


async def test_quit_while_the_vehicle_lands_says_it_goes_on_landing(make_app):
    app = make_app(fc="sim", takeoff_alt=3.0)
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        await pilot.press("a", "y")
        await wait_for(pilot, lambda: armed(app), what="the vehicle to arm")
        await pilot.press("t", "y")
        await wait_for(pilot, lambda: (v := app.core.telemetry.snapshot()).in_air and (v.rel_alt_m or 0) > 2,
                       timeout=30, what="the vehicle to climb")
        await pilot.press("l")
        await wait_for(pilot, lambda: app.core.telemetry.snapshot().flight_mode == "LAND", what="LAND mode")
        await pilot.press("q")
        assert isinstance(app.screen, ConfirmScreen)
        assert app.screen.asked() == "The vehicle is ARMED. Quit? It is left in LAND mode."
        await pilot.press("y")
        await wait_for(pilot, lambda: app.core.state is CoreState.STOPPED, what="the core to stop")
        assert in_log(app, "vehicle left in LAND mode at exit: a hold would interrupt it")
        assert not in_log(app, "vehicle put in hold before exit")


async def test_the_precland_key_needs_a_processor_that_reports_a_landing_target(make_app):
    app = make_app(fc="sim")
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        assert app.screen.active_bindings["p"][2] is False  # the recording processor has no getLandingTarget
        await pilot.press("p")
        await pilot.pause(0.2)
        assert "precland" not in tui_commands(app)
    app = make_app(fc="sim", processor="precision_land")
    async with app.run_test(size=(80, 24)) as pilot:
        await started(pilot)
        assert app.screen.active_bindings["p"][2] is True
        await pilot.press("p")  # on the ground: sent, and the platform says why it does not land
        await wait_for(pilot, lambda: "precland" in tui_commands(app), what="precland")
