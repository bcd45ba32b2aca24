"""The autonomy gate of a replay: on exactly when it was on in the recorded run; nothing is ever sent."""

from __future__ import annotations

import asyncio
import bisect
import csv
from pathlib import Path
from typing import Protocol

import msgspec

from controllers.base import FlightController, RecordedVehicle
from controllers.replay_timeline import ReplayTimeline
from sources.buffer import Frame
from uav_tui.config import SafetyConfig
from uav_tui.events import EventLog
from uav_tui.flight.autonomy import AutonomyGate, Decision
from uav_tui.flight.telemetry import TelemetryManager
from uav_tui.hosting.host import ProcessedFrame, StageClock
from uav_tui.hosting.wire import FrameOutcome


class ReplayedController(FlightController, RecordedVehicle, Protocol):
    """The controller of a replay: a flight controller that replays a recorded run's vehicle."""


def autonomy_switches(events_csv: Path) -> list[tuple[int, bool]]:
    """(t_mono_ns, on) each time autonomy was switched on or off in a recorded run, oldest first.

    Read from events.csv's ``autonomy`` column (True, False, or empty for other events). Runs recorded
    before that column existed say it only in the message: there, an ``autonomy`` event whose message starts
    with "autonomy ON" or "autonomy OFF" is taken as the switch.
    """
    switches = []
    if events_csv.is_file():
        with open(events_csv, newline="") as handle:
            reader = csv.DictReader(handle)
            switched = _switch if "autonomy" in (reader.fieldnames or ()) else _switch_in_message
            for row in reader:
                on = switched(row)
                if on is not None and row.get("t_mono_ns"):
                    switches.append((int(row["t_mono_ns"]), on))
    switches.sort()
    return switches


def _switch(row: dict[str, str]) -> bool | None:
    return {"True": True, "False": False}.get(row.get("autonomy") or "")


def _switch_in_message(row: dict[str, str]) -> bool | None:
    """The switch in a run recorded without the ``autonomy`` column: the event's text says it."""
    message = row.get("message") or ""
    if row.get("kind") != "autonomy" or not message.startswith(("autonomy ON", "autonomy OFF")):
        return None
    return message.startswith("autonomy ON")


def stage_clock(timeline: ReplayTimeline) -> StageClock:
    """What moves a replayed frame's stage times onto the replay's clock, where its capture time is.

    The stages keep their real durations, and so does the frame's wait for the processor: a paced replay shows a
    frame when its recorded time comes, and a busy processor takes it later, as in a live run; a frame shown late
    (a loaded computer) counts the delay as waiting too. Lockstep waits for the processor before it shows a frame,
    so processing starts at the capture time. Latency and processing times read as in a live run, not as this
    computer's uptime minus the recorded one.
    """

    def on_replay_clock(frame: Frame, outcome: FrameOutcome) -> FrameOutcome:
        shown = timeline.real_ns(frame.t_mono_ns)
        shift = frame.t_mono_ns - (outcome.t_start_ns if shown is None else shown)
        return msgspec.structs.replace(outcome, t_start_ns=outcome.t_start_ns + shift,
                                       t_end_ns=outcome.t_end_ns + shift if outcome.t_end_ns else 0,
                                       t_vector_ns=outcome.t_vector_ns + shift if outcome.t_vector_ns else 0)

    return on_replay_clock


class ReplayGate(AutonomyGate):
    """Judges every replayed vector as the recorded run's gate would have, on the recorded clock.

    Autonomy counts as on for a frame when it was on at the frame's capture time in ``events.csv``;
    the frame's age is taken on the replay's clock (zero in lockstep: the replay waits for it). The
    decision is recorded in ``frames.csv``; the vector is never sent anywhere.
    """

    def __init__(self, safety: SafetyConfig, telemetry: TelemetryManager, events: EventLog,
                 controller: ReplayedController) -> None:
        super().__init__(safety, telemetry, events)
        self.controller = controller
        self.clock = controller.timeline.now
        self.switches = autonomy_switches(controller.run_dir / "events.csv")
        self._times = [t for t, _ in self.switches]

    def enabled_at(self, t_mono_ns: int) -> bool:
        """Whether autonomy was on in the recorded run at ``t_mono_ns``."""
        index = bisect.bisect_right(self._times, t_mono_ns)
        return index > 0 and self.switches[index - 1][1]

    def consider(self, result: ProcessedFrame) -> Decision:
        self.enabled = self.enabled_at(result.frame.t_mono_ns)
        decision = super().consider(result)
        self._pending = None  # judged and recorded, never sent
        return decision

    async def run(self) -> None:
        """Nothing to send: a replayed vector never leaves the platform."""
        await asyncio.Event().wait()

    async def watch(self, *_: object) -> None:
        """No watchdog: whether autonomy is on comes from the recording, frame by frame."""
