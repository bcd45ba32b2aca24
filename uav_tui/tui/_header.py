"""The status bar at the top: link, flight state, GPS, battery, and the autonomy switch."""

from __future__ import annotations

from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Horizontal
from textual.reactive import reactive
from textual.widgets import Static

from uav_tui.status import CoreStatus
from uav_tui.tui._panel import MISSING, StatusPanel, num


class VehicleLine(StatusPanel):
    """Two lines: connection and link age; flight mode, armed / in air, GPS fix, battery."""

    DEFAULT_CSS = """
    VehicleLine { border-top: none; padding: 0 1; width: 1fr; height: 2; }
    """

    def __init__(self, link_timeout: float) -> None:
        super().__init__()
        self.link_timeout = link_timeout
        """Heartbeat age from which the link shows as LOST (``safety.link_timeout``, as the gate uses)."""

    def describe(self, status: CoreStatus) -> Text:
        t = status.telemetry
        line = Text(no_wrap=True, overflow="ellipsis")
        label = self.get_component_rich_style("panel--label")
        if status.fc == "none":
            line.append("fc ", label).append("none").append("\n")
            return line.append(self.styled("no vehicle: commands are refused", "warn"))
        age = status.heartbeat_age_s
        line.append("link ", label)  # first: a long connection string may be cut, the link state never
        if age is None or age >= self.link_timeout:
            line.append(self.styled("LOST" + ("" if age is None or age == float("inf") else f" {age:.1f}s"), "bad"))
        else:
            line.append(self.styled(f"ok {age:.1f}s", "good"))
        line.append("  fc ", label).append(status.fc_description or status.fc).append("\n")
        if status.vehicle_problem:
            return line.append(self.styled(status.vehicle_problem, "bad"))
        if status.link_lost:
            line.append(self.styled("STALE", "warn")).append(" ")
        line.append(t.flight_mode or MISSING).append("  ")
        line.append(self.styled("ARMED", "warn") if t.armed else Text("disarmed"))
        line.append("  ").append("IN AIR" if t.in_air else "on ground")
        line.append("  gps ", self.get_component_rich_style("panel--label"))
        line.append(f"{t.gps_fix or MISSING} {num(t.satellites, 'd')} sat")
        battery = num(t.battery_pct, ".0f", "%")
        line.append("  bat ", self.get_component_rich_style("panel--label"))
        low = t.battery_pct is not None and t.battery_pct < 25
        line.append(self.styled(battery, "bad") if low else Text(battery))
        if t.battery_v is not None:
            line.append(f" {t.battery_v:.1f}V")
        return line


class AutonomyBadge(Static):
    """AUTONOMY ON / OFF, in colours no one can miss (set by the ``-on`` class)."""

    DEFAULT_CSS = """
    AutonomyBadge {
        width: 14; height: 2; content-align: center middle; text-style: bold;
        background: $success; color: $text;
        &.-on { background: $error; color: $text; }
    }
    """

    on: reactive[bool] = reactive(False, toggle_class="-on")
    """Autonomy enabled: the processor's vectors may fly the vehicle."""

    def render(self) -> str:
        return "AUTONOMY\n>>> ON <<<" if self.on else "AUTONOMY\nOFF"


class StatusBar(Horizontal):
    """The header: :class:`VehicleLine` and :class:`AutonomyBadge`.

    Args:
        link_timeout: heartbeat age (s) from which the link shows as lost.
    """

    DEFAULT_CSS = """
    StatusBar { height: 2; dock: top; background: $panel; }
    """

    def __init__(self, link_timeout: float) -> None:
        super().__init__()
        self.link_timeout = link_timeout

    def compose(self) -> ComposeResult:
        yield VehicleLine(self.link_timeout)
        yield AutonomyBadge()

    def show(self, status: CoreStatus) -> None:
        self.query_one(VehicleLine).status = status
        self.query_one(AutonomyBadge).on = status.autonomy
