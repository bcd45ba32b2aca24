"""Modal screens of the dashboard."""

from __future__ import annotations

from uav_tui.tui.screens.confirm import ConfirmScreen

__all__ = ["ConfirmScreen"]
