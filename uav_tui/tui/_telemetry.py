"""The telemetry panel: position, altitude, attitude, velocity and distance from home."""

from __future__ import annotations

import math

from rich.text import Text

from uav_tui.status import CoreStatus
from uav_tui.tui._panel import MISSING, StatusPanel, num


class TelemetryPanel(StatusPanel):
    """Where the vehicle is and how it moves (NED relative to home, degrees, m/s)."""

    TITLE = "Telemetry"

    def describe(self, status: CoreStatus) -> Text:
        t = status.telemetry
        if status.fc == "none":
            return self.rows(("fc", self.styled("none: no flight controller (--fc)", "warn")))
        home = MISSING
        if t.north_m is not None and t.east_m is not None:
            home = f"{math.hypot(t.north_m, t.east_m):.1f} m (N {t.north_m:.1f} E {t.east_m:.1f})"
        return self.rows(
            ("pos", f"{num(t.lat_deg, '.6f')} {num(t.lon_deg, '.6f')}"),
            ("alt", f"{num(t.rel_alt_m, '.1f', ' m')} rel  {num(t.abs_alt_m, '.1f', ' m')} amsl"),
            ("att", f"r {num(t.roll_deg, '5.1f')} p {num(t.pitch_deg, '5.1f')} y {num(t.yaw_deg, '5.1f')}"),
            ("vel", f"N {num(t.vn_ms, '.1f')} E {num(t.ve_ms, '.1f')} D {num(t.vd_ms, '.1f')} m/s"),
            ("home", home),
        )
