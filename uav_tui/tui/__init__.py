"""The Textual terminal UI: ``run_tui(config)`` runs the core inside the dashboard.

See :mod:`uav_tui.tui.app` for the dashboard and :mod:`uav_tui.tui._session` for signals, scripts,
``--duration`` and ``--on-hangup``.
"""

from __future__ import annotations

from uav_tui.tui._session import run_tui
from uav_tui.tui.app import KEYS, UavApp

__all__ = ["KEYS", "UavApp", "run_tui"]
