"""The gimbal relay's gate, on a stand-in controller: sent only while autonomy is on with a fresh frame and a live
link, one send at a time, stopped when the pointing stops, released on every stop and never taken back after it."""

from __future__ import annotations

import asyncio
import time
from dataclasses import dataclass, field

import numpy as np
import pytest

from controllers.errors import NotSupported
from processors import GimbalPointing
from processors.outputs import FrameOutputs
from sources.buffer import Frame
from uav_tui.config import SafetyConfig
from uav_tui.events import EventLog
from uav_tui.flight.autonomy import AutonomyGate
from uav_tui.flight.plausibility import REFUSALS_TO_STOP
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.wire import FrameOutcome
from uav_tui.relays.gimbal import GimbalRelay, say_no_gimbal


@dataclass
class _Gimbal:
    """A flight controller with a gimbal, as far as the relay uses one; ``delay_s`` per call."""

    description: str = "stand-in"
    heartbeat_s: float = 0.0
    delay_s: float = 0.0
    calls: list[tuple[str, ...]] = field(default_factory=list)
    gimbal_controlled: bool = False
    vector_active: bool = False

    def heartbeat_age_s(self) -> float:
        return self.heartbeat_s

    async def point_gimbal(self, mode: str, pitch: float, yaw: float) -> None:
        await asyncio.sleep(self.delay_s)
        self.gimbal_controlled = True
        self.calls.append((mode, f"{pitch:g}", f"{yaw:g}"))

    async def release_gimbal(self) -> None:
        await asyncio.sleep(self.delay_s)
        self.gimbal_controlled = False
        self.calls.append(("release",))


def _result(pointing: GimbalPointing | None, age_s: float = 0.0) -> ProcessedFrame:
    frame = Frame(np.zeros((4, 4, 3), np.uint8), 1, time.monotonic_ns() - int(age_s * 1e9), time.time_ns())
    return ProcessedFrame(frame, FrameOutcome(0, 0, outputs=FrameOutputs(gimbal=pointing)))


def _relay(vehicle: _Gimbal) -> tuple[GimbalRelay, AutonomyGate]:
    events = EventLog()
    gate = AutonomyGate(SafetyConfig(), TelemetryManager(None), events)
    gate.controller = vehicle  # type: ignore[assignment]
    return GimbalRelay(vehicle, gate, SafetyConfig(), events), gate  # type: ignore[arg-type]


TURN = GimbalPointing.rates(-5.0, 10.0)


async def test_sent_only_while_autonomy_is_on_the_frame_fresh_and_the_link_alive() -> None:
    vehicle = _Gimbal()
    relay, gate = _relay(vehicle)
    judged = []
    for age, heartbeat, on in ((0.0, 0.0, False), (0.0, 0.0, True), (0.6, 0.0, True), (0.0, 2.0, True)):
        vehicle.heartbeat_s = heartbeat
        if on and not gate.enabled:
            gate.enable("test")
        judged.append(relay.consider(_result(TURN, age)))
        await relay.sender.settle()
    assert judged == ["not sent: autonomy off", "sent", "not sent: frame 0.60 s old",
                      "not sent: link lost (heartbeat 2.0 s old)"]
    assert vehicle.calls == [("rate", "-5", "10")] and relay.sent == 1


async def test_one_send_at_a_time_and_a_stop_when_the_pointing_stops() -> None:
    vehicle = _Gimbal(delay_s=0.05)
    relay, gate = _relay(vehicle)
    gate.enable("test")
    first, second = relay.consider(_result(TURN)), relay.consider(_result(TURN))
    assert (first, second) == ("sent", "not sent: the previous one is still being sent")
    await relay.sender.settle()
    lost = relay.consider(_result(None))  # the target is lost: a gimbal turning at a rate is stopped
    await relay.sender.settle()
    again = relay.consider(_result(None))  # and told once
    assert (lost, again) == ("stopped (no pointing)", "")
    assert vehicle.calls == [("rate", "-5", "10"), ("rate", "0", "0")]


@pytest.mark.parametrize("reason", [None, "processor raised 5 times in a row"], ids=["operator", "watchdog"])
async def test_every_stop_releases_and_a_send_under_way_does_not_take_control_back(reason: str | None) -> None:
    vehicle = _Gimbal(delay_s=0.05)
    relay, gate = _relay(vehicle)
    gate.enable("test")
    relay.consider(_result(TURN))
    await asyncio.sleep(0.01)  # the send is under way ...
    await gate.disable("test", reason, hold=False)  # ... when autonomy stops
    relay.consider(_result(TURN))  # a frame judged after the stop
    await relay.close()
    assert vehicle.calls == [("rate", "-5", "10"), ("release",)] and not vehicle.gimbal_controlled
    assert relay.releases == 1
    assert [e.message for e in relay.events.recent if "gimbal" in e.message] == \
        [f"gimbal stopped and released: {reason or 'operator'}"]


async def test_a_stop_before_the_send_starts_drops_it() -> None:
    vehicle = _Gimbal()
    relay, gate = _relay(vehicle)
    gate.enable("test")
    relay.consider(_result(TURN))  # judged, not started yet
    await gate.disable("test", hold=False)
    await relay.close()
    assert vehicle.calls == [] and relay.releases == 0  # never controlled: nothing to release


async def test_without_gimbal_control_the_frame_says_so() -> None:
    assert say_no_gimbal(_result(TURN)) == "not sent: the flight controller has no gimbal control"
    assert say_no_gimbal(_result(None)) == ""


@dataclass
class _Refusing(_Gimbal):
    """A gimbal controller whose sends raise ``error`` (a refusal below the controller's errors, or no gimbal)."""

    error: Exception = field(default_factory=lambda: ValueError("gimbal setpoint angle (1e30, 0): finite values"))

    async def point_gimbal(self, mode: str, pitch: float, yaw: float) -> None:
        raise self.error


async def test_a_pointing_changed_after_it_was_built_is_refused_and_a_run_stops_the_gimbal() -> None:
    vehicle = _Gimbal()
    relay, gate = _relay(vehicle)
    gate.enable("test")
    relay.consider(_result(TURN))
    await relay.sender.settle()
    judged = []
    for _ in range(REFUSALS_TO_STOP + 1):
        pointing = GimbalPointing.angles(-10.0, 0.0)
        object.__setattr__(pointing, "pitch", 1e30)
        judged.append(relay.consider(_result(pointing)))
    await asyncio.sleep(0)
    assert relay._release is not None
    await relay._release
    assert set(judged) == {"refused: gimbal angle pitch=1e+30 deg is out of range [-90, 90]"}
    assert vehicle.calls == [("rate", "-5", "10"), ("release",)] and relay.refusals.refused == REFUSALS_TO_STOP + 1
    messages = [e.message for e in relay.events.recent]
    assert any(m.startswith(f"gimbal output stopped: {REFUSALS_TO_STOP} gimbal pointings in a row refused") for m in
               messages)
    # a true one again: still stopped until autonomy is next turned on
    assert relay.consider(_result(TURN)).startswith("not sent: stopped until autonomy is next turned on")
    await gate.disable("test", "operator")
    await relay.close()
    gate.enable("test")
    assert relay.consider(_result(TURN)) == "sent"


async def test_a_send_that_raises_is_an_event_never_a_lost_task_exception(caplog: pytest.LogCaptureFixture) -> None:
    vehicle = _Refusing()
    relay, gate = _relay(vehicle)
    gate.enable("test")
    for _ in range(3):
        relay.consider(_result(TURN))
        await relay.sender.settle()
    assert relay.failed == 3 and relay.sent == 0
    said = [e.message for e in relay.events.recent if e.level == "warning"]
    assert said == ["gimbal setpoint not sent: ValueError: gimbal setpoint angle (1e30, 0): finite values"]  # once
    assert "Task exception was never retrieved" not in caplog.text


async def test_a_vehicle_without_a_gimbal_is_said_in_every_later_frame() -> None:
    vehicle = _Refusing(error=NotSupported("gimbal: the vehicle has no gimbal MAVSDK can find"))
    relay, gate = _relay(vehicle)
    gate.enable("test")
    judged = []
    for _ in range(3):
        judged.append(relay.consider(_result(TURN)))
        await relay.sender.settle()
    assert judged == ["sent"] + ["not sent: gimbal: the vehicle has no gimbal MAVSDK can find"] * 2
    assert relay.failed == 1
