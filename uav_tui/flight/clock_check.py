"""This computer's clock against the autopilot's GPS time, said once per run when they differ.

A Raspberry Pi has no clock that runs while it is off (the Pi 5's needs a battery fitted) and in the
field no network time: it starts from the time it last saved, hours or days behind. Run folder names,
every ``t_wall_ns`` and the events' times then carry that time. The autopilot knows UTC from GPS
(SYSTEM_TIME), so the run can say so, and ``telemetry.csv``'s ``fc_clock_offset_ms`` corrects them.
"""

from __future__ import annotations

from controllers.base import Telemetry
from uav_tui.events import EventLog

CLOCK_OFF_S = 2.0
"""A difference from which the clock counts as wrong (network time keeps it within milliseconds)."""


class ClockCheck:
    """A telemetry listener: the first known offset, if at least :data:`CLOCK_OFF_S`, becomes a warning."""

    def __init__(self, events: EventLog) -> None:
        self.events = events
        self.checked = False

    def __call__(self, telemetry: Telemetry) -> None:
        offset_ms = telemetry.fc_clock_offset_ms
        if self.checked or offset_ms is None:
            return
        self.checked = True
        if advice := clock_advice(offset_ms):
            self.events.emit("warning", "platform", advice)


def clock_advice(offset_ms: int) -> str:
    """What to say about a GPS time ``offset_ms`` ahead of this computer's clock: "" when under :data:`CLOCK_OFF_S`."""
    if abs(offset_ms) < CLOCK_OFF_S * 1000:
        return ""
    seconds = round(offset_ms / 1000)
    direction = "behind" if seconds > 0 else "ahead of"
    return (f"this computer's clock is {duration(abs(seconds))} {direction} the autopilot's GPS time (no network "
            "time?): run folder names and t_wall_ns use this computer's clock, and telemetry.csv's "
            f"fc_clock_offset_ms corrects them; to set the clock: sudo date -s \"@$(( $(date +%s) {seconds:+d} ))\"")


def duration(seconds: int) -> str:
    """``3 d 4 h``, ``2 h 5 min``, ``12 min 30 s``, ``45 s``: the two largest units."""
    parts: list[str] = []
    for unit, size in (("d", 86400), ("h", 3600), ("min", 60), ("s", 1)):
        if seconds >= size or (unit == "s" and not parts):
            parts.append(f"{seconds // size} {unit}")
            seconds %= size
    return " ".join(parts[:2])
