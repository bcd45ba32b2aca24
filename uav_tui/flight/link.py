"""Link loss and recovery as events, and a dead built-in simulator reported as such.

Without it a lost link was silent while autonomy was off: only the heartbeat age grew, and the
status kept showing the last flight state as if it were current.
"""

from __future__ import annotations

import asyncio
import time

from controllers.base import FlightController, SimulatorOwner
from uav_tui.events import EventLog

CHECK_PERIOD_S = 0.2


class LinkWatch:
    """Follows one controller's heartbeat age; emits ``link`` events when it crosses ``link_timeout``.

    Args:
        controller: the connected flight controller.
        events: where the events go (every interface and events.csv read them).
        link_timeout: heartbeat age (s) from which the link counts as lost (as the autonomy gate uses).
    """

    def __init__(self, controller: FlightController, events: EventLog, link_timeout: float) -> None:
        self.controller = controller
        self.events = events
        self.link_timeout = link_timeout
        self.lost = False
        """The heartbeat is older than ``link_timeout``: telemetry shown is stale."""
        self.vehicle_problem = ""
        """Why the vehicle cannot come back (the built-in simulator's process ended), or ""."""
        self._lost_at = 0.0

    async def run(self) -> None:
        """Check every :data:`CHECK_PERIOD_S` until cancelled."""
        while True:
            self.check()
            await asyncio.sleep(CHECK_PERIOD_S)

    def check(self) -> None:
        age = self.controller.heartbeat_age_s()
        if age >= self.link_timeout and not self.lost:
            self.lost, self._lost_at = True, time.monotonic() - age
            self.events.emit("warning", "link", f"link lost: no heartbeat for {age:.1f} s; the vehicle state shown "
                             "is stale (autonomy cannot fly)")
        elif age < self.link_timeout and self.lost:
            self.lost = False
            self.events.emit("info", "link", f"link restored after {time.monotonic() - self._lost_at:.1f} s")
        ended = self.controller.sim.exit_status() if isinstance(self.controller, SimulatorOwner) else None
        if ended and not self.vehicle_problem:
            self.vehicle_problem = f"simulator process {ended}"
            self.events.emit("error", "link", f"the built-in simulator process {ended}: the vehicle is gone; "
                             "restart uav-tui")
