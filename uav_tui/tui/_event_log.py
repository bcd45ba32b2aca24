"""The event log panel: operator commands, autonomy decisions, warnings and errors, newest last; and what
the processor prints."""

from __future__ import annotations

import time
from typing import ClassVar

from rich.style import Style
from rich.text import Text
from textual import events
from textual.widgets import RichLog

from uav_tui.events import Event
from uav_tui.output.line_budget import LineBudget, LineSplitter
from uav_tui.output.text import safe, shorten

PRINT_CHARS = 500
"""A longer printed line is cut."""

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
        self._printed = LineBudget(self._show_printed, self._show_left_out)
        self._lines = {False: LineSplitter("\n", PRINT_CHARS), True: LineSplitter("\n", PRINT_CHARS)}
        """What was printed to stdout (False) and stderr (True), cut into lines."""

    def on_mount(self) -> None:
        self.border_title = "Events"
        self.app.begin_capture_print(self)

    def add_event(self, event: Event) -> None:
        """Append one event."""
        style = self.get_component_rich_style(f"log--{event.level}") if event.level != "info" else None
        origin = f"[{event.origin}] " if event.origin not in ("platform", "tui") else ""
        self._write(event.t_wall_ns / 1e9, f"{LEVEL_MARK[event.level]} {event.kind}: {origin}{event.message}", style)

    def on_print(self, event: events.Print) -> None:
        """What is printed in the platform's process (the processor's ``print()``, in either isolation), a line
        at a time within a :class:`LineBudget`: with no terminal of its own, it would be lost."""
        for line in self._lines[event.stderr].feed(event.text):
            if line.strip():
                self._printed.line(("stderr: " if event.stderr else "print: ") + safe(shorten(line, PRINT_CHARS)))

    def _show_printed(self, text: str) -> None:
        self._write(time.time(), f"  {text}")

    def _show_left_out(self, count: int) -> None:
        self._write(time.time(), f"! {count} more printed lines not shown (too many at once)",
                    self.get_component_rich_style("log--warning"))

    def _write(self, t_wall_s: float, text: str, style: Style | None = None) -> None:
        line = Text(time.strftime("%H:%M:%S ", time.localtime(t_wall_s)), self.get_component_rich_style("log--time"))
        line.append(text, style)
        self.write(line)
