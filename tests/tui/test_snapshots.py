"""Snapshots of the dashboard (pytest-textual-snapshot): 80x24, 120x40, a confirmation, the keyboard ROI box.

Everything that changes by itself is frozen: the panels read a fixed :class:`CoreStatus`, the preview
a fixed synthetic frame, and the event log holds fixed events; the vehicle is the real simulator (so
the vehicle keys are enabled) but its live numbers never reach the screen. Update the SVGs with
``pytest tests/tui/test_snapshots.py --snapshot-update`` and look at them before committing.
"""

from __future__ import annotations

import time

import pytest

from controllers.base import Telemetry
from sources.synthetic import SyntheticScene
from uav_tui.core import UavCore
from uav_tui.events import Event
from uav_tui.flight.autonomy import Verdict
from uav_tui.hosting.host import HostPhase, HostState, ProcessorState
from uav_tui.stats import PipelineStats
from uav_tui.status import CoreStatus
from uav_tui.tui._event_log import EventLogView
from uav_tui.tui.app import UavApp

from .conftest import started

T0 = 1_790_000_000_000_000_000  # fixed wall clock of the fixed events (ns)

STATUS = CoreStatus(
    telemetry=Telemetry(lat_deg=47.397742, lon_deg=8.545594, abs_alt_m=498.3, rel_alt_m=9.8, roll_deg=-1.2,
                        pitch_deg=2.5, yaw_deg=87.0, north_m=12.0, east_m=-5.0, down_m=-9.8, vn_ms=0.4,
                        ve_ms=-0.1, vd_ms=0.0, battery_v=15.6, battery_pct=76.0, flight_mode="OFFBOARD",
                        armed=True, in_air=True, gps_fix="3D", satellites=14),
    pipeline=PipelineStats(capture_fps=30.0, processed_fps=29.8, frame_age_ms=3.0, latency_ms_p95=9.5,
                           processing_ms_p50=4.2, processing_ms_p95=7.9, frames_processed=1790, frames_skipped=12,
                           errors=1, busy_ms=0.0),
    source_uri="synthetic:?fps=30",
    source={"width": 640, "height": 480},
    processor="tests/tui/procs.py:RecordingProcessor",
    capabilities=frozenset({"catch_cmd", "customize_processing", "getPreparedVector"}),
    processor_error="ValueError: no target in frame 1203",
    fc="sim",
    fc_description="simulated vehicle (udpin://0.0.0.0:14540)",
    heartbeat_age_s=0.2,
    autonomy=True,
    autonomy_stop_reason="",
    last_vector=(0.35, -0.2, 1.0),
    last_decision="executed",
    last_verdict=Verdict.EXECUTED,
    vectors_executed=42,
    vectors_rejected=1,
    recording={"run_dir": "runs/2026-11-22T08-00-00Z", "frames_saved": 57, "dropped": 3},
    box=(300, 200, 120, 90),
    processor_state=ProcessorState("process", HostPhase(HostState.RUNNING), 4242, 38.0),
)

EVENTS = [
    Event(T0, 0, "info", "platform", "started: source synthetic:?fps=30, fc sim"),
    Event(T0 + 4_000_000_000, 0, "info", "command", "arm", "tui"),
    Event(T0 + 9_000_000_000, 0, "info", "command", "takeoff", "tui"),
    Event(T0 + 21_000_000_000, 0, "info", "autonomy", "autonomy ON", "tui"),
    Event(T0 + 30_000_000_000, 0, "warning", "autonomy", "frame 1190: vector rejected: non-finite", "processor"),
    Event(T0 + 31_000_000_000, 0, "error", "processor", "frame 1203: ValueError: no target in frame 1203"),
]

FRAME = SyntheticScene(640, 480, seed=0).render(40)
TRACKED = STATUS.box
"""The processor's box on the fixed frame: outlined in the preview, shown in the algorithm panel."""


@pytest.fixture
def dashboard(make_config, monkeypatch):
    monkeypatch.setenv("TZ", "UTC")
    time.tzset()
    yield UavApp(UavCore(make_config(fc="sim")), status=lambda: STATUS, frames=lambda: (1, FRAME, TRACKED))
    monkeypatch.delenv("TZ")
    time.tzset()


async def freeze(pilot) -> None:
    """Wait for the real core, then replace everything that moves by the fixed values."""
    app = await started(pilot)
    log = app.query_one(EventLogView)
    app.core.events.remove_listener(app.on_core_event)
    log.clear()
    for event in EVENTS:
        log.add_event(event)
    app.clear_notifications()
    app.refresh_status()
    await pilot.pause(0.3)


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_dashboard(snap_compare, dashboard, size):
    assert snap_compare(dashboard, terminal_size=size, run_before=freeze)


def test_arm_confirmation(snap_compare, dashboard):
    assert snap_compare(dashboard, press=["a"], run_before=freeze)


def test_keyboard_roi_box(snap_compare, dashboard):
    assert snap_compare(dashboard, press=["b", "right", "right", "shift+down"], run_before=freeze)
