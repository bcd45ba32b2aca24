"""The gate's decisions carry a Verdict beside their text, and the watchdog's causes decide whether it holds."""

from __future__ import annotations

import asyncio
import copy
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from controllers.base import Telemetry, VectorEnd, VectorEndKind
from sources.buffer import Frame
from uav_tui.config import SafetyConfig
from uav_tui.events import EventLog
from uav_tui.flight.autonomy import AutonomyGate, Verdict
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.wire import FrameOutcome


@dataclass
class _Vehicle:
    """A flight controller and its telemetry, as far as the gate reads them."""

    flight_mode: str = "HOLD"
    vector_active: bool = False
    last_vector_end: VectorEnd = VectorEnd(VectorEndKind.COMPLETED)
    vectors: list[tuple[float, float, float]] = field(default_factory=list)
    holds: int = 0

    def snapshot(self) -> Telemetry:
        return Telemetry(armed=True, in_air=True, flight_mode=self.flight_mode, rel_alt_m=3.0)  # in the height band

    def heartbeat_age_s(self) -> float:
        return 0.0

    async def set_fly_vector(self, vx: float, vy: float, t: float, *, yield_to_others: bool = False) -> None:
        self.vectors.append((vx, vy, t))
        self.vector_active = True

    async def hold(self) -> None:
        self.holds += 1


def _gate(vehicle: _Vehicle) -> AutonomyGate:
    gate = AutonomyGate(SafetyConfig(max_speed=1.0), vehicle, EventLog())
    gate.controller = vehicle
    return gate


def _result(vector: object, error: str | None = None) -> ProcessedFrame:
    return ProcessedFrame(Frame(np.zeros((4, 4, 3), np.uint8), 1, time.monotonic_ns(), time.time_ns()),
                          FrameOutcome(0, 0, vector=vector, error=error))


def test_each_decision_has_its_verdict_and_reads_as_before() -> None:
    vehicle = _Vehicle()
    gate = _gate(vehicle)
    decided = []
    nan = float("nan")
    for vector, error in ((None, None), (None, "ValueError"), ((nan, 0.0, 1.0), None), ((0.5, 0.0, 1.0), None)):
        decision = gate.consider(_result(vector, error))
        decided.append((decision.verdict, str(decision)))
    gate.enable("test")
    for vector in ((0.5, 0.0, 1.0), (3.0, 0.0, 1.0)):
        decision = gate.consider(_result(vector))
        decided.append((decision.verdict, str(decision)))
    assert decided[:2] == [(Verdict.NO_VECTOR, "no vector"), (Verdict.ERROR, "error")]
    assert decided[2][0] is Verdict.REJECTED and decided[2][1].startswith("rejected: non-finite")
    assert decided[3:5] == [(Verdict.NOT_EXECUTED, "not executed: autonomy off"), (Verdict.EXECUTED, "executed")]
    assert decided[5][0] is Verdict.EXECUTED and decided[5][1].startswith("executed (clamped (3, 0, 1) to (1, 0, 1)")
    assert gate.last_decision == decided[5][1] and gate.last_decision.verdict is Verdict.EXECUTED
    assert copy.deepcopy(gate.last_decision).verdict is Verdict.EXECUTED  # CoreStatus.as_dict deep-copies it


async def _until(condition: Callable[[], object], what: str) -> None:
    for _ in range(100):
        if condition():
            return
        await asyncio.sleep(0.02)
    raise AssertionError(f"timed out waiting for {what}")


async def test_the_watchdog_leaves_a_vehicle_taken_over_alone_and_holds_on_a_camera_stall() -> None:
    vehicle = _Vehicle()
    gate = _gate(vehicle)
    frame_age: list[float | None] = [0.0]
    tasks = [asyncio.create_task(gate.run()), asyncio.create_task(gate.watch(lambda: frame_age[0], lambda: 0.0,
                                                                             lambda: 0))]
    try:
        gate.enable("test")
        gate.consider(_result((0.5, 0.0, 1.0)))
        await _until(lambda: vehicle.vectors, "the vector to fly")
        vehicle.flight_mode = "POSCTL"  # a pilot took the sticks while the vector flew
        await _until(lambda: not gate.enabled, "autonomy to stop")
        assert "took over" in gate.stop_reason and vehicle.holds == 0  # a hold would override the pilot

        vehicle.flight_mode = "HOLD"
        gate.enable("test")
        frame_age[0] = None  # no frame: the camera stalled
        await _until(lambda: not gate.enabled, "autonomy to stop")
        assert gate.stop_reason == "camera stalled" and vehicle.holds == 1  # the running vector is stopped
    finally:
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
