"""Flying the vehicle back to a point and holding there: ``lost_action = "last_seen"``.

The controller contract has no go-to (:class:`controllers.base.FlightController`), so the vehicle is flown back
with its own vectors: a short body-frame vector towards the point every :data:`STEP_S`, recomputed from the newest
telemetry, slowing over the last metres, kept inside the envelope's radius and polygon; then it holds. It lets go
without a hold when the flight mode leaves the platform's own (a pilot, a mission or a failsafe has the vehicle) or
the link goes quiet (the heartbeat older than ``link_timeout``: no vector is flown on a position that old; the last
one ends within :data:`VECTOR_S` and the autopilot's own link-loss action follows), and holds where it is when the
position is lost, the envelope refuses the way or the time it allows runs out.
"""

from __future__ import annotations

import asyncio
import math
import time

from controllers.base import FlightController
from uav_tui.errors import KNOWN_ERRORS
from uav_tui.events import EventLog
from uav_tui.flight.envelope import Envelope
from uav_tui.flight.envelope_shape import Point
from uav_tui.flight.telemetry import TelemetryManager

ARRIVED_M = 0.3
"""Closer than this to the point, the vehicle holds."""

STEP_S = 0.2
"""A new vector this often (each lasts :data:`VECTOR_S`, so the stream never pauses between them)."""

VECTOR_S = 0.5
"""Each vector's duration: if this loop dies, the last one ends within it and the controller holds."""

GAIN_PER_S = 1.0
"""Speed towards the point per metre still to go (m/s per m), up to the configured ``max_speed``."""

SPARE_S = 10.0
"""Time allowed beyond the straight flight at ``max_speed`` (twice over) before it gives up and holds."""


async def fly_back(controller: FlightController, telemetry: TelemetryManager, envelope: Envelope,
                   events: EventLog, point: Point, *, max_speed: float, link_timeout: float,
                   modes: frozenset[str]) -> None:
    """Fly to ``point`` (north, east from home) at up to ``max_speed`` and hold there; see the module docstring."""
    north, east = point
    where = f"where the target was last seen ({north:.1f} m N, {east:.1f} m E)"
    deadline: float | None = None
    while True:
        t = telemetry.snapshot()
        if t.flight_mode not in modes:
            events.emit("warning", "autonomy", f"flying back to {where} stopped: the vehicle is in {t.flight_mode} "
                        "mode (the pilot, a mission or a failsafe has it)", "envelope")
            return
        if (age := t.heartbeat_age_s) is None or age >= link_timeout:
            events.emit("warning", "autonomy", f"flying back to {where} stopped: the link is quiet (heartbeat "
                        f"{'never heard' if age is None else f'{age:.1f} s old'}); the autopilot's link-loss action "
                        "has the vehicle", "envelope")
            return
        if t.north_m is None or t.east_m is None or t.yaw_deg is None:
            note = "no position or heading"
            break
        dn, de = north - t.north_m, east - t.east_m
        distance = math.hypot(dn, de)
        deadline = deadline or time.monotonic() + 2 * distance / max_speed + SPARE_S
        if distance < ARRIVED_M:
            note = f"back at {where}, {distance:.1f} m off"
            break
        if time.monotonic() > deadline:
            note = f"{distance:.1f} m short of {where} when its time ran out"
            break
        scale = min(max_speed, GAIN_PER_S * distance) / distance  # m/s per metre of the offset
        yaw = math.radians(t.yaw_deg)
        forward = (dn * math.cos(yaw) + de * math.sin(yaw)) * scale
        right = (-dn * math.sin(yaw) + de * math.cos(yaw)) * scale
        confined = envelope.keep_inside((forward, right, VECTOR_S), t)
        if confined.vector is None:
            note = f"{distance:.1f} m short of {where}: {confined.note}"
            break
        try:
            await controller.set_fly_vector(*confined.vector)
        except KNOWN_ERRORS as exc:
            events.emit("error", "autonomy", f"flying back to {where} failed: {exc}", "envelope")
            return
        await asyncio.sleep(STEP_S)
    try:
        await controller.hold()
    except KNOWN_ERRORS as exc:
        events.emit("error", "autonomy", f"{note}; the hold failed: {exc}; take over with the remote", "envelope")
        return
    events.emit("info", "autonomy", f"{note}: holding", "envelope")
