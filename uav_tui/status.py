"""The snapshot of a running core that every interface renders."""

from __future__ import annotations

import enum
from dataclasses import asdict, dataclass, field, fields, replace
from typing import Any

from controllers.base import Telemetry
from uav_tui.flight.autonomy import Verdict
from uav_tui.flight.geolocate import GeoFix, describe
from uav_tui.hosting.host import ProcessorState
from uav_tui.output.text import safe
from uav_tui.stats import PipelineStats


class CoreState(enum.Enum):
    """Where a core is in its life; it starts once and stops once."""

    NEW = "new"  # constructed, nothing opened
    RUNNING = "running"  # start() finished: frames flow, commands are accepted
    STOPPED = "stopped"  # stop() finished: everything released


def saves_dropped_text(counts: dict[str, int]) -> str:
    """``40 saves dropped (38 throttled, 2 outside a frame)``; "" when none was."""
    if not counts:
        return ""
    return f"{sum(counts.values())} saves dropped ({', '.join(f'{n} {why}' for why, n in counts.items())})"


@dataclass(frozen=True)
class CoreStatus:
    """What the TUI, the headless status line and the web page show.

    Its text is safe to show as it is: every string in it (the processor's name and last exception, the
    camera's URI and properties, the recorder's paths, the host's state) is passed through :func:`safe`
    when the snapshot is made, so no interface can forget to: passwords hidden, control characters escaped.
    """

    telemetry: Telemetry
    pipeline: PipelineStats
    source_uri: str
    source: dict[str, Any]
    processor: str
    capabilities: frozenset[str]
    processor_error: str | None
    fc: str
    fc_description: str
    heartbeat_age_s: float | None
    autonomy: bool
    autonomy_stop_reason: str
    last_vector: tuple[float, float, float] | None
    last_decision: str
    vectors_executed: int
    vectors_rejected: int
    recording: dict[str, Any] = field(default_factory=dict)
    """Run folder, frames saved, rows written, drops (empty when recording is off)."""
    startup_s: float | None = None
    """Seconds from the process start to the first processed frame (None before it)."""
    processor_state: ProcessorState | None = None
    """Where the processor runs and how it is doing: running, restarting N, crashed: reason; PID, memory."""
    link_lost: bool = False
    """No heartbeat for ``link_timeout``: the telemetry is stale (as old as ``heartbeat_age_s``)."""
    vehicle_problem: str = ""
    """Why the vehicle cannot come back (e.g. the built-in simulator's process was killed), or ""."""
    box: tuple[int, int, int, int] | None = None
    """The processor's ``box`` on the newest processed frame (frame pixels), None when it tracks nothing."""
    target: GeoFix | None = None
    """Where ``box`` is on the ground, from the telemetry at that frame's capture; None: no box."""
    last_verdict: Verdict | None = None
    """What ``last_decision`` decided (None before the first vector)."""
    saves_dropped: dict[str, int] = field(default_factory=dict)
    """``tmMgr.save`` calls not stored, by why: ``throttled`` (above ``save_max_hz``; counted where the processor runs
    in the platform's process, ``isolation = "thread"``), ``not recorded`` (recording is off), ``outside a frame``
    (called outside ``photo_processing``). Only the non-zero counts."""
    precland: bool = False
    """``precland`` is on: the processor's landing targets are sent to the autopilot."""
    precland_stop_reason: str = ""
    """Why ``precland`` was turned off last ("" while on or never on)."""
    landing_targets_sent: int = 0
    """LANDING_TARGET messages sent to the autopilot."""
    landing_targets_failed: int = 0
    """Landing targets the controller could not send (the reason is in the event log)."""

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, str):
                object.__setattr__(self, f.name, safe(value))
            elif isinstance(value, dict):
                object.__setattr__(self, f.name, {k: safe(v) if isinstance(v, str) else v for k, v in value.items()})
        if self.processor_state is not None:
            object.__setattr__(self, "processor_state", replace(self.processor_state,
                                                                state=safe(self.processor_state.state)))

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready form (for ``--json`` and the web page)."""
        data = asdict(self)
        data["capabilities"] = sorted(self.capabilities)
        data["last_verdict"] = self.last_verdict.value if self.last_verdict is not None else None
        if self.target is not None:
            data["target"].update(distance_m=self.target.distance_m, bearing_deg=self.target.bearing_deg,
                                  range_m=self.target.range_m, description=describe(self.target))
        return data
