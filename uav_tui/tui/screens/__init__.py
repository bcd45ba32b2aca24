"""Modal screens of the dashboard."""

from __future__ import annotations

from uav_tui.tui.screens.confirm import ConfirmScreen
from uav_tui.tui.screens.prompt import CommandPrompt

__all__ = ["CommandPrompt", "ConfirmScreen"]
