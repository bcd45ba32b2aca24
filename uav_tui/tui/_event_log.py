"""The event log panel: operator commands, autonomy decisions, warnings and errors, newest last."""

from __future__ import annotations

import time
from typing import ClassVar

from rich.text import Text
from textual.widgets import RichLog

from uav_tui.events import Event

LEVEL_MARK = {"info": " ", "warning": "!", "error": "X"}
"""One character per level, so the log reads without colours too."""


class EventLogView(RichLog):
    """Shows :class:`~uav_tui.events.Event` s as ``HH:MM:SS ! kind: message`` lines."""

    COMPONENT_CLASSES: ClassVar[set[str]] = {"log--time", "log--warning", "log--error"}
    DEFAULT_CSS = """
    EventLogView {
        border-top: solid $primary; border-title-color: $text-primary; border-title-style: bold;
        height: 1fr; padding: 0 1; background: $surface; scrollbar-size-vertical: 1;
        & > .log--time { color: $text-muted; }
        & > .log--warning { color: $text-warning; }
        & > .log--error { color: $text-error; text-style: bold; }
    }
    """

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__(id=id, max_lines=500, min_width=20, wrap=True, markup=False, auto_scroll=True)

    def on_mount(self) -> None:
        self.border_title = "Events"

    def add_event(self, event: Event) -> None:
        """Append one event."""
        clock = time.strftime("%H:%M:%S", time.localtime(event.t_wall_ns / 1e9))
        line = Text(f"{clock} ", self.get_component_rich_style("log--time"))
        style = self.get_component_rich_style(f"log--{event.level}") if event.level != "info" else None
        origin = f"[{event.origin}] " if event.origin not in ("platform", "tui") else ""
        line.append(f"{LEVEL_MARK[event.level]} {event.kind}: {origin}{event.message}", style)
        self.write(line)
