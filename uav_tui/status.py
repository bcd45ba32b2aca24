"""The snapshot of a running core that every interface renders."""

from __future__ import annotations

import enum
from dataclasses import asdict, dataclass, field, fields, replace
from typing import TYPE_CHECKING, Any

from controllers.base import Telemetry
from uav_tui.flight.autonomy import Verdict
from uav_tui.flight.geo_detections import LocatedDetection, count_tracks, describe_shown, locate_shown
from uav_tui.flight.geolocate import GeoFix, describe, locate_row
from uav_tui.flight.track_lock import LockState
from uav_tui.hosting.host import ProcessorHost, ProcessorState
from uav_tui.output.text import safe
from uav_tui.relays.registry import gimbal_relay
from uav_tui.stats import PipelineStats

if TYPE_CHECKING:
    from controllers.base import FlightController
    from uav_tui.camera.active import ActiveCamera
    from uav_tui.flight.autonomy import AutonomyGate
    from uav_tui.flight.link import LinkWatch
    from uav_tui.flight.telemetry import TelemetryManager
    from uav_tui.flight.track_lock import TrackLock
    from uav_tui.recording import Recorder
    from uav_tui.relays.contract import HandledFrame, OutputRelay
    from uav_tui.relays.precland import LandingTargetFeed
    from uav_tui.start_parts import Parts


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


@dataclass(frozen=True, kw_only=True)
class ProcessorSection:
    """The source and the processor: what runs on which frames, and how fast."""

    pipeline: PipelineStats
    source_uri: str
    source: dict[str, Any]
    processor: str
    capabilities: frozenset[str]
    processor_state: ProcessorState | None = None
    """Where the processor runs and how it is doing (running, restarting N, crashed: reason), its PID, memory."""


@dataclass(frozen=True, kw_only=True)
class SeenSection:
    """What the newest processed frame saw."""

    box: tuple[int, int, int, int] | None = None
    """The processor's ``box`` on the newest processed frame (frame pixels; the lock's while it steers), None when it
    tracks nothing."""
    target: GeoFix | None = None
    """Where ``box`` is on the ground, from the telemetry at that frame's capture; None: no box."""
    detections: tuple[LocatedDetection, ...] = ()
    """The most confident of the processor's ``detections`` on that frame, geo-located likewise (at most
    :data:`~uav_tui.flight.geo_detections.MAX_SHOWN`)."""
    detections_total: int = 0
    """How many detections that frame had."""
    tracks_total: int = 0
    """How many tracks those detections are of (each detection's ``track_id``: :mod:`uav_tui.hosting.tracks`)."""


@dataclass(frozen=True, kw_only=True)
class VehicleSection:
    """The vehicle: its telemetry and its link."""

    telemetry: Telemetry
    fc: str
    fc_description: str
    heartbeat_age_s: float | None
    link_lost: bool = False
    """No heartbeat for ``link_timeout``: the telemetry is stale (as old as ``heartbeat_age_s``)."""
    vehicle_problem: str = ""
    """Why the vehicle cannot come back (e.g. the built-in simulator's process was killed), or ""."""


@dataclass(frozen=True, kw_only=True)
class AutonomySection:
    """Autonomy, its vectors and the operator's lock on a track."""

    autonomy: bool
    autonomy_stop_reason: str
    last_vector: tuple[float, float, float] | None
    last_decision: str
    vectors_executed: int
    vectors_rejected: int
    last_verdict: Verdict | None = None
    """What ``last_decision`` decided (None before the first vector)."""
    lock: str = ""
    """The operator's lock on a track (:mod:`uav_tui.flight.track_lock`): ``locked on #3 car``, ``#3 car lost 1.2 s``;
    "" when nothing is locked."""


@dataclass(frozen=True, kw_only=True)
class OutputsSection:
    """What the output relays did, the landing targets' feed and the gimbal."""

    relayed: dict[str, dict[str, int]] = field(default_factory=dict)
    """What each output relay did so far (its ``counts``: ``sent``, ``failed``), by the output it relays
    (:data:`~uav_tui.relays.registry.REGISTRY`): ``{"gimbal": {"sent": 210, "failed": 0}, ...}``."""
    precland: bool = False
    """``precland`` is on: the processor's landing targets are sent to the autopilot."""
    precland_stop_reason: str = ""
    """Why ``precland`` was turned off last ("" while on or never on)."""
    landing_targets_sent: int = 0
    """LANDING_TARGET messages sent to the autopilot."""
    landing_targets_failed: int = 0
    """Landing targets the controller could not send (the reason is in the event log)."""
    landing_targets_refused: int = 0
    """Landing targets that could not be true (:mod:`uav_tui.flight.plausibility`), never sent."""
    landing_none_reason: str = ""
    """Why there is no landing target now: ``refused: ...`` or ``the processor says: ...`` ("" while there is)."""
    gimbal_sent: int = 0
    """Gimbal setpoints sent (the processor's ``getGimbalPointing``)."""
    gimbal_failed: int = 0
    """Gimbal setpoints the controller could not send (the reason is in the event log)."""
    gimbal_controlled: bool = False
    """The platform holds control of the gimbal."""


@dataclass(frozen=True, kw_only=True)
class RunSection:
    """The run itself: the processor's newest error, the recording, the start-up time, the dropped saves."""

    processor_error: str | None
    recording: dict[str, Any] = field(default_factory=dict)
    """Run folder, frames saved, rows written, drops (empty when recording is off)."""
    startup_s: float | None = None
    """Seconds from the process start to the first processed frame (None before it)."""
    saves_dropped: dict[str, int] = field(default_factory=dict)
    """``tmMgr.save`` calls not stored, by why: ``throttled`` (above ``save_max_hz``), ``not recorded`` (recording
    is off), ``outside a frame`` (called outside ``photo_processing``). Only the non-zero counts."""


Section = ProcessorSection | SeenSection | VehicleSection | AutonomySection | OutputsSection | RunSection


@dataclass(frozen=True, kw_only=True)
class CoreStatus(RunSection, OutputsSection, AutonomySection, VehicleSection, SeenSection, ProcessorSection):
    """What the TUI, the headless status line and the web page show: the fields of its sections, flat (in the
    order ``processor``, ``seen``, ``vehicle``, ``autonomy``, ``outputs``, ``run``: the bases', last first).

    Its text is safe to show as it is: every string in it (the processor's name and last exception, the
    camera's URI and properties, the recorder's paths, the host's state) is passed through :func:`safe`
    when the snapshot is made, so no interface can forget to: passwords hidden, control characters escaped.
    """

    @classmethod
    def of(cls, *sections: Section) -> CoreStatus:
        """The status made of ``sections``, one of each (each type-checked where it is built)."""
        return cls(**{f.name: getattr(section, f.name) for section in sections for f in fields(section)})

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, str):
                object.__setattr__(self, f.name, safe(value))
            elif isinstance(value, dict):
                object.__setattr__(self, f.name, {k: safe(v) if isinstance(v, str) else v for k, v in value.items()})
        if self.processor_state is not None:
            phase = self.processor_state.phase
            object.__setattr__(self, "processor_state", replace(self.processor_state,
                                                                phase=replace(phase, reason=safe(phase.reason))))

    def gimbal_summary(self) -> str:
        """``gimbal P-45 Y120 (controlled, 210 sent)``: the gimbal's attitude (pitch from the horizon, yaw from north)
        where there is one, and what the processor's pointing did; "" with neither."""
        t = self.telemetry
        parts = []
        if t.gimbal_pitch_deg is not None and t.gimbal_yaw_deg is not None:
            parts.append(f"P{t.gimbal_pitch_deg:+.0f} Y{t.gimbal_yaw_deg % 360:03.0f}")
        if "getGimbalPointing" in self.capabilities:
            sent = f"{self.gimbal_sent} sent" + (f", {self.gimbal_failed} failed" if self.gimbal_failed else "")
            parts.append(f"({'controlled, ' if self.gimbal_controlled else ''}{sent})")
        return "gimbal " + " ".join(parts) if parts else ""

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready form (for ``--json`` and the web page)."""
        data = asdict(self)
        data["capabilities"] = sorted(self.capabilities)
        data["last_verdict"] = self.last_verdict.value if self.last_verdict is not None else None
        data["gimbal"] = self.gimbal_summary()
        if self.processor_state is not None:  # the page shows the text; the typed parts ride along in "phase"
            data["processor_state"]["state"] = str(self.processor_state.phase)
        if self.target is not None:
            data["target"].update(distance_m=self.target.distance_m, bearing_deg=self.target.bearing_deg,
                                  range_m=self.target.range_m, description=describe(self.target))
        data["detections_description"] = describe_shown(self.detections, self.detections_total, self.tracks_total)
        for shown, located in zip(data["detections"], self.detections, strict=True):
            shown["target"].update(distance_m=located.target.distance_m, bearing_deg=located.target.bearing_deg)
        return data


def core_status(parts: Parts, last: HandledFrame | None, recorder: Recorder | None, processor_error: str | None,
                startup_s: float | None) -> CoreStatus:
    """Everything an interface shows of a running core (its ``parts``, its newest handled frame, its ``recorder``,
    the last line of the newest processor error, the seconds to the first processed frame), as one immutable
    snapshot: each part of it read by a section given the few parts it shows."""
    return CoreStatus.of(
        _processor(parts.worker, parts.camera, parts.config.source),
        _seen(last, parts.camera, parts.telemetry),
        _vehicle(parts.controller, parts.telemetry, parts.link, parts.config.fc),
        _autonomy(parts.gate, parts.lock),
        _outputs(parts.relays, parts.landing),
        RunSection(processor_error=processor_error, recording=recorder.status() if recorder is not None else {},
                   startup_s=startup_s, saves_dropped=_saves_dropped(parts.worker, parts.telemetry, recorder)),
    )


def _processor(worker: ProcessorHost, camera: ActiveCamera, configured: str) -> ProcessorSection:
    source = camera.source
    assert source is not None
    properties = source.get_properties()
    return ProcessorSection(pipeline=worker.snapshot(), source_uri=properties.get("uri", configured), source=properties,
                            processor=worker.processor.info.name, capabilities=worker.processor.info.capabilities,
                            processor_state=worker.state())


def _seen(last: HandledFrame | None, camera: ActiveCamera, telemetry: TelemetryManager) -> SeenSection:
    """The newest processed frame's ``box`` and detections, each located on the ground."""
    box = last.outcome.box if last is not None else None
    found = (last.outcome.detections or ()) if last is not None else ()
    # where they were seen: with the telemetry at that frame's capture, not the newest (~20 us a box)
    seen = asdict(telemetry.at(last.frame.t_mono_ns)[0]) if last is not None and (box or found) else {}
    at_ns = last.frame.t_mono_ns if last is not None else None
    return SeenSection(box=box, target=None if box is None else locate_row(camera.model, box, seen, at_ns=at_ns),
                       detections=locate_shown(found, camera.model, seen, at_ns), detections_total=len(found),
                       tracks_total=count_tracks(found))


def _vehicle(controller: FlightController | None, telemetry: TelemetryManager, link: LinkWatch | None,
             fc: str) -> VehicleSection:
    return VehicleSection(telemetry=telemetry.snapshot(), fc=fc,
                          fc_description=controller.description if controller is not None else "none",
                          heartbeat_age_s=controller.heartbeat_age_s() if controller else None,
                          link_lost=link is not None and link.lost,
                          vehicle_problem=link.vehicle_problem if link is not None else "")


def _autonomy(gate: AutonomyGate, lock: TrackLock) -> AutonomySection:
    return AutonomySection(autonomy=gate.enabled, autonomy_stop_reason=gate.stop_reason, last_vector=gate.last_vector,
                           last_decision=gate.last_decision, last_verdict=gate.last_decision.verdict,
                           vectors_executed=gate.executed, vectors_rejected=gate.rejected,
                           lock="" if lock.state is LockState.OFF else str(lock.status()))


def _outputs(relays: dict[str, OutputRelay], landing: LandingTargetFeed) -> OutputsSection:
    gimbal = gimbal_relay(relays)
    relayed = {name: dict(relay.counts) for name, relay in relays.items()}
    sent, pointed = relayed.get("landing_target", {}), relayed.get("gimbal", {})
    return OutputsSection(relayed=relayed, precland=landing.engaged, precland_stop_reason=landing.stop_reason,
                          landing_targets_sent=sent.get("sent", 0), landing_targets_failed=sent.get("failed", 0),
                          landing_targets_refused=landing.refusals.refused, landing_none_reason=landing.why_none,
                          gimbal_sent=pointed.get("sent", 0), gimbal_failed=pointed.get("failed", 0),
                          gimbal_controlled=gimbal is not None and gimbal.controller.gimbal_controlled)


def _saves_dropped(worker: ProcessorHost, telemetry: TelemetryManager, recorder: Recorder | None) -> dict[str, int]:
    """``tmMgr.save`` calls not stored, by why (see ``CoreStatus.saves_dropped``)."""
    counts = {"throttled": worker.saves_throttled,
              "not recorded": telemetry.saves_dropped,
              "outside a frame": recorder.misplaced_saves if recorder is not None else 0}
    return {why: count for why, count in counts.items() if count}
